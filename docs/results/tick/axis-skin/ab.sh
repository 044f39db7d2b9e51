#!/bin/bash
# main against the change, alternated: ab.sh MAIN_BINARY AXIS_BINARY ROUNDS. The cube motions
# and graze over 3 repeats: cubes-{main,axis}-rK.txt in the current directory.
set -eu
for r in $(seq 1 "$3"); do
  for v in main axis; do
    B=$1; [ $v = axis ] && B=$2
    "$B" bench tick --motion rest --motion graze --motion walk --motion trapped --motion sweep \
      --ticks 20000 --repeats 3 > "cubes-$v-r$r.txt" 2>&1
  done
done
