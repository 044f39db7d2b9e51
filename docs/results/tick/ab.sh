#!/bin/bash
# Two hapto binaries side by side, alternated: ab.sh A_BINARY B_BINARY A_NAME B_NAME ROUNDS
# Each round runs A, then B, in the current directory: rest and the 10^6-triangle sphere on its
# default index, each tick's own time over 5 repeats (s6-NAME-rK.txt), then rest, walk, trapped
# and sweep over 3 repeats (cubes-NAME-rK.txt; CUBE_MOTIONS="rest graze walk ..." names other
# cube motions). Medians: own_medians.py . s6 A_NAME B_NAME 1,2,...
set -eu
if [ $# -ne 5 ]; then
  sed -n 2,6p "$0" >&2
  exit 2
fi
for r in $(seq 1 "$5"); do
  for side in a b; do
    if [ $side = a ]; then bin=$1 name=$3; else bin=$2 name=$4; fi
    "$bin" bench tick --motion rest --motion sphere --objects 1000000 --index octree:8:0.00028 \
      --ticks 20000 --repeats 5 > "s6-$name-r$r.txt" 2>&1
    cubes=()
    for m in ${CUBE_MOTIONS:-rest walk trapped sweep}; do cubes+=(--motion "$m"); done
    "$bin" bench tick "${cubes[@]}" --ticks 20000 --repeats 3 > "cubes-$name-r$r.txt" 2>&1
  done
done
