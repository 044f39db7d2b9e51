#!/bin/bash
# Near triangles passed over by their bounding ball, against main, alternated:
#   ab.sh MAIN_BINARY BALL_BINARY ROUNDS
# Each round runs main, then the change: the 10^6- and 10^3-triangle spheres on their default
# indexes and the cube motions, each tick's own time over 5 repeats. Output: s6-*, s3-*,
# cubes-* (main or ball, round K) here.
set -e
for r in $(seq 1 "$3"); do
  for v in main ball; do
    if [ "$v" = main ]; then b="$1"; else b="$2"; fi
    "$b" bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 \
      --ticks 20000 --repeats 5 > "s6-$v-r$r.txt" 2>&1
    "$b" bench tick --motion rest --motion sphere --objects 1000 --index octree:8:0.005 \
      --ticks 20000 --repeats 5 > "s3-$v-r$r.txt" 2>&1
    "$b" bench tick --motion rest --motion walk --motion trapped --motion sweep --motion graze \
      --ticks 20000 --repeats 5 > "cubes-$v-r$r.txt" 2>&1
  done
done
