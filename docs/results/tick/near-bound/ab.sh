#!/bin/bash
# main against the change, alternated: ab.sh MAIN_BINARY BOUND_BINARY ROUNDS
# (each round: main, then the change; rest and the 10^6-triangle sphere on its default index,
# each tick's own time over 5 repeats, then the cube motions over 3 repeats).
# Output: s6-{main,bound}-rK.txt and cubes-{main,bound}-rK.txt here.
set -e
for r in $(seq 1 "$3"); do
  for v in main bound; do
    B=$1; [ $v = bound ] && B=$2
    "$B" bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 \
      --ticks 20000 --repeats 5 > "s6-$v-r$r.txt" 2>&1
    "$B" bench tick --motion rest --motion walk --motion trapped --motion sweep \
      --ticks 20000 --repeats 3 > "cubes-$v-r$r.txt" 2>&1
  done
done
