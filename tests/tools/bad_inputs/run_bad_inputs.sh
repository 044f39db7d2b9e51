#!/usr/bin/env bash
# Runs the bad-input corpus (cases.tsv next to this script) against the hapto command.
#
#   run_bad_inputs.sh [--from DIR] HAPTO [CASE...]   every case, or only the named ones
#   run_bad_inputs.sh --prepare DIR                   makes DIR's scratch folder and snapshot
#
# Every case starts from the same scratch folder: a copy of the corpus, a folder (adir), a
# FIFO nobody writes (fifo), a Unix socket nobody listens on (sock), outputs that already
# exist (outputs/*) and a symlink to an input (outputs/link.json -> ../scenes/ok.json). It is
# made and snapshotted once (by --prepare into DIR, which ctest runs once per run as the
# cases' fixture, or at the start of a run without --from), and each case gets a copy of it
# (cp -a keeps the FIFO, the socket and the symlink as they are). For each case the script
# runs `hapto ARGS` from its copy under `timeout 20` and checks that
#   - it ends by itself within 20 s (a FIFO or /dev/zero must not make it hang),
#   - it exits with code 2 (bad input),
#   - its output contains the case's text (the message names the offending thing),
#   - the scratch folder is exactly as before: the same names (no temporary files left) and
#     byte-identical files (no input overwritten, no existing output touched), compared with
#     the snapshot taken of the folder it was copied from (a copy that differed would fail the
#     case, never pass it).
# Prints one line per case and exits 1 when any case failed.
set -u

usage() {
    echo "usage: $0 [--from DIR] HAPTO [CASE...] | --prepare DIR" >&2
    exit 64
}
corpus=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
table="$corpus/cases.tsv"

# Every name in the folder with its type, and a checksum of every regular file (one find: the
# after-snapshot is taken once per case).
snapshot() {
    (cd "$1" && find . -mindepth 1 -printf '%y %p\n' -type f -exec sha256sum {} + | LC_ALL=C sort)
}

# Makes DIR/scratch (the folder every case starts from) and DIR/snapshot (its snapshot). A DIR
# already holding the same snapshot is left as it is, so cases of another run in the same build
# folder that are copying it meanwhile are not disturbed; otherwise DIR is replaced.
prepare() {
    local dir=$1 new
    mkdir -p "$(dirname "$dir")" || return 1
    new=$(mktemp -d "$dir.new.XXXXXX") || return 1
    local scratch="$new/scratch"
    mkdir "$scratch" &&
        cp -R "$corpus/scenes" "$corpus/devices" "$corpus/points" "$corpus/traces" "$corpus/reports" "$scratch/" &&
        mkdir "$scratch/adir" "$scratch/outputs" &&
        mkfifo "$scratch/fifo" &&
        # A Unix socket (a special file every command must refuse); perl-base is always
        # installed and starts in a fraction of python3's time.
        perl -MIO::Socket::UNIX -e 'IO::Socket::UNIX->new(Local => $ARGV[0]) or die "$ARGV[0]: $!\n"' "$scratch/sock" &&
        printf 'a report from before\n' >"$scratch/outputs/report.json" &&
        printf 'point,candidates\n0,1\n' >"$scratch/outputs/out.csv" &&
        printf '{"an": "older scene"}\n' >"$scratch/outputs/scene.json" &&
        ln -s ../scenes/ok.json "$scratch/outputs/link.json" &&
        snapshot "$scratch" >"$new/snapshot" || { rm -rf "$new"; return 1; }
    if [[ -d $dir/scratch ]] && cmp -s "$new/snapshot" "$dir/snapshot"; then
        rm -rf "$new"
        return 0
    fi
    rm -rf "$dir" && mv "$new" "$dir" || { rm -rf "$new"; return 1; }
}

run_case() {
    local name=$1 expect=$2 args=$3
    local scratch
    scratch=$(mktemp -d "${TMPDIR:-/tmp}/hapto-bad-input.XXXXXX")
    if ! cp -a "$from/scratch/." "$scratch/"; then
        rm -rf "$scratch"
        echo "FAIL $name: could not copy the scratch folder $from/scratch"
        return 1
    fi
    local before after output code
    before=$(<"$from/snapshot")
    # eval: the arguments are a bash fragment (process substitutions such as <(cat f)).
    output=$(cd "$scratch" && eval "timeout -k 5 20 \"\$hapto\" $args" 2>&1 </dev/null)
    code=$?
    after=$(snapshot "$scratch")
    local problems=()
    if [[ $code -eq 124 || $code -eq 137 ]]; then
        problems+=("did not finish within 20 s")
    elif [[ $code -ne 2 ]]; then
        problems+=("exit code $code, expected 2")
    fi
    if [[ $output != *"$expect"* ]]; then
        problems+=("the message does not contain '$expect'")
    fi
    if [[ $before != "$after" ]]; then
        problems+=("the scratch folder changed: $(diff <(echo "$before") <(echo "$after") |
            grep '^[<>]' | tr '\n' ';' | cut -c1-400)")
    fi
    rm -rf "$scratch"
    if [[ ${#problems[@]} -eq 0 ]]; then
        echo "ok   $name"
        return 0
    fi
    echo "FAIL $name: hapto $args"
    local p
    for p in "${problems[@]}"; do
        echo "       - $p"
    done
    echo "       output: $(echo "$output" | head -c 600 | tr '\n' ' ')"
    return 1
}

from= own_from=
case ${1:-} in
    --prepare)
        [[ $# -eq 2 ]] || usage
        prepare "$2" || { echo "could not make the scratch folder in $2" >&2; exit 1; }
        exit 0
        ;;
    --from)
        [[ $# -ge 3 ]] || usage
        from=$2
        shift 2
        [[ -d $from/scratch && -f $from/snapshot ]] ||
            { echo "no scratch folder in $from (run --prepare $from first)" >&2; exit 64; }
        ;;
esac
[[ $# -ge 1 ]] || usage
hapto=$(realpath "$1")
shift
[[ -x $hapto ]] || { echo "not an executable: $hapto" >&2; exit 64; }
if [[ -z $from ]]; then
    own_from=$(mktemp -d "${TMPDIR:-/tmp}/hapto-bad-input-from.XXXXXX")
    trap 'rm -rf "$own_from"' EXIT
    from="$own_from/dir"
    prepare "$from" || { echo "could not make the scratch folder in $from" >&2; exit 1; }
fi

declare -A wanted=()
for c in "$@"; do
    wanted[$c]=1
done
failed=0 ran=0
while IFS=$'\t' read -r name expect args; do
    [[ -z $name || $name == \#* ]] && continue
    [[ $# -gt 0 && -z ${wanted[$name]:-} ]] && continue
    [[ -n $expect && -n $args ]] || { echo "FAIL $name: malformed line in $table"; failed=$((failed + 1)); continue; }
    unset "wanted[$name]"
    ran=$((ran + 1))
    run_case "$name" "$expect" "$args" || failed=$((failed + 1))
done <"$table"
for c in "${!wanted[@]}"; do
    echo "FAIL $c: no such case in $table"
    failed=$((failed + 1))
done
echo "$ran cases, $failed failed"
[[ $failed -eq 0 && $ran -gt 0 ]]
