#!/bin/bash
# The side-by-side runs of this directory: `main` (hapto-base) and another build (hapto-NAME),
# release binaries copied beside the run directory, alternated round by round.
#   ab.sh NAME ROUNDS    e.g. `ab.sh resume 5` (full/), `ab.sh lean 4` (lean/)
set -euo pipefail
name=$1
rounds=$2
for r in $(seq 1 "$rounds"); do
    for b in base "$name"; do
        ../hapto-$b bench tick --motion rest --motion walk --motion trapped --motion sweep \
            --ticks 20000 --repeats 5 > "cubes-$b-r$r.txt" 2>&1
        ../hapto-$b bench tick --motion rest --motion sphere --objects 1000000 \
            --index octree:8:0.00028 --ticks 20000 --repeats 5 > "sphere-$b-r$r.txt" 2>&1
    done
done
