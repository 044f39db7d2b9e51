#!/bin/bash
# main against the change, alternated: ab.sh MAIN_BINARY FACES_BINARY ROUNDS. It is ../ab.sh
# with the names main and faces: s6-{main,faces}-rK.txt and cubes-{main,faces}-rK.txt in the
# current directory.
exec "$(dirname "$0")/../ab.sh" "$1" "$2" main faces "$3"
