#!/bin/bash
# Alternates main (base) and the lean resume, 4 rounds each.
cd /tmp/scr/ab3
for r in 1 2 3 4; do
  for b in base lean; do
    ../hapto-$b bench tick --motion rest --motion walk --motion trapped --motion sweep --ticks 20000 --repeats 5 > cubes-$b-r$r.txt 2>&1
    ../hapto-$b bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 --ticks 20000 --repeats 5 > sphere-$b-r$r.txt 2>&1
  done
done
echo done > finished
