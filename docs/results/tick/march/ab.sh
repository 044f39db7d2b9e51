#!/bin/bash
# main against the change, alternated: ab.sh MAIN_BINARY V3_BINARY ROUNDS. It is ../ab.sh
# with the names main and v3: s6-{main,v3}-rK.txt and cubes-{main,v3}-rK.txt in the
# current directory.
exec "$(dirname "$0")/../ab.sh" "$1" "$2" main v3 "$3"
