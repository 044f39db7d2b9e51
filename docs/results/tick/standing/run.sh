#!/bin/bash
# Issue 39 item 2, where it stands: every motion over 10^6 objects or triangles, then rest and the
# sphere at 10^6 and at 10^3 triangles on one index, each tick's own time over 5 repeats, ROUNDS
# rounds in the current directory: run.sh HAPTO_BINARY ROUNDS. Medians: standing.py . ROUNDS SPHERE_ROUNDS
set -eu
if [ $# -ne 2 ]; then
  sed -n 2,4p "$0" >&2
  exit 2
fi
for r in $(seq 1 "$2"); do
  "$1" bench tick --motion all --ticks 20000 --repeats 5 > "all-r$r.txt" 2>&1
  for n in 1000000 1000; do
    out=s6; [ "$n" = 1000 ] && out=s3
    "$1" bench tick --motion rest --motion sphere --objects "$n" --index octree:8:0.00028 \
      --ticks 20000 --repeats 5 > "$out-r$r.txt" 2>&1
  done
done
