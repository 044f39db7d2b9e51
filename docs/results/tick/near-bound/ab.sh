#!/bin/bash
# main against the change, alternated: ab.sh MAIN_BINARY BOUND_BINARY ROUNDS. It is ../ab.sh
# with the names main and bound: s6-{main,bound}-rK.txt and cubes-{main,bound}-rK.txt in the
# current directory.
exec "$(dirname "$0")/../ab.sh" "$1" "$2" main bound "$3"
