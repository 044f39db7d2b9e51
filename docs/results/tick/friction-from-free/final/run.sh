#!/bin/bash
# hapto-main: the release binary of main at f3c10ba; hapto-new2: the same with 76282f7.
# Rounds alternate the two binaries; nothing else ran on the machine but round 1 (a build).
cd "$(dirname "$0")"
for r in 1 2 3 4 5; do
  for b in main new2; do
    ../hapto-$b bench tick --motion all --ticks 20000 --repeats 5 > all-$b-r$r.txt 2>&1
    ../hapto-$b bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 --ticks 20000 --repeats 5 > s6-$b-r$r.txt 2>&1
    ../hapto-$b bench tick --motion rest --motion sphere --objects 1000 --index octree:8:0.005 --ticks 20000 --repeats 5 > s3-$b-r$r.txt 2>&1
  done
done
echo done > finished
