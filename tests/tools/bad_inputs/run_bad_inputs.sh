#!/usr/bin/env bash
# Runs the bad-input corpus (cases.tsv next to this script) against the hapto command.
#
#   run_bad_inputs.sh HAPTO [CASE...]     every case, or only the named ones
#
# For each case, in a fresh scratch folder holding a copy of the corpus, a folder (adir), a
# FIFO nobody writes (fifo), a Unix socket nobody listens on (sock), outputs that already
# exist (outputs/*) and a symlink to an input (outputs/link.json -> ../scenes/ok.json), it
# runs `hapto ARGS` from that folder under `timeout 20` and checks that
#   - it ends by itself within 20 s (a FIFO or /dev/zero must not make it hang),
#   - it exits with code 2 (bad input),
#   - its output contains the case's text (the message names the offending thing),
#   - the scratch folder is exactly as before: the same names (no temporary files left) and
#     byte-identical files (no input overwritten, no existing output touched).
# Prints one line per case and exits 1 when any case failed.
set -u

if [[ $# -lt 1 ]]; then
    echo "usage: $0 HAPTO [CASE...]" >&2
    exit 64
fi
hapto=$(realpath "$1")
shift
corpus=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
table="$corpus/cases.tsv"
[[ -x $hapto ]] || { echo "not an executable: $hapto" >&2; exit 64; }

# Every name in the folder with its type, and a checksum of every regular file.
snapshot() {
    (cd "$1" && find . -mindepth 1 -printf '%y %p\n' | LC_ALL=C sort &&
        find . -type f -print0 | LC_ALL=C sort -z | xargs -0 -r sha256sum)
}

run_case() {
    local name=$1 expect=$2 args=$3
    local scratch
    scratch=$(mktemp -d "${TMPDIR:-/tmp}/hapto-bad-input.XXXXXX")
    cp -R "$corpus/scenes" "$corpus/devices" "$corpus/points" "$corpus/traces" "$corpus/reports" "$scratch/"
    mkdir "$scratch/adir" "$scratch/outputs"
    mkfifo "$scratch/fifo"
    # A Unix socket (a special file every command must refuse); perl-base is always installed
    # and starts in a fraction of python3's time, which mattered over ~250 cases per preset.
    perl -MIO::Socket::UNIX -e 'IO::Socket::UNIX->new(Local => $ARGV[0]) or die "$ARGV[0]: $!\n"' "$scratch/sock"
    printf 'a report from before\n' >"$scratch/outputs/report.json"
    printf 'point,candidates\n0,1\n' >"$scratch/outputs/out.csv"
    printf '{"an": "older scene"}\n' >"$scratch/outputs/scene.json"
    ln -s ../scenes/ok.json "$scratch/outputs/link.json"
    local before after output code
    before=$(snapshot "$scratch")
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
