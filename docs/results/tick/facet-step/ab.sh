#!/bin/bash
# The facet step against main, alternated: ab.sh MAIN_BINARY FACET_BINARY ROUNDS
# (each round: main, then the step; rest and the 10^6-triangle sphere on its default index,
# each tick's own time over 5 repeats). Output: s6-main-rK.txt, s6-facet-rK.txt here.
set -e
for r in $(seq 1 "$3"); do
  "$1" bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 \
    --ticks 20000 --repeats 5 > "s6-main-r$r.txt" 2>&1
  "$2" bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 \
    --ticks 20000 --repeats 5 > "s6-facet-r$r.txt" 2>&1
done
