#!/usr/bin/env bash
# Runs every libFuzzer target for a bounded time (default 60 s each).
#   tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
# Builds the `fuzz` preset (clang, ASan + UBSan + libFuzzer) into build/fuzz. Each target
# starts from its committed seed corpus tools/fuzz/corpus/<name>/ and grows a scratch corpus
# in build/fuzz/corpus/<name>/. Crashes land in build/fuzz/crashes/<name>/; fix the bug, then
# copy the crash input into tools/fuzz/corpus/<name>/ so the ctest replay keeps it fixed.
# The whole fuzzer output of a run is kept in build/fuzz/logs/<name>.log; the summary printed
# here is the final status line (coverage, corpus, exec/s), the final stats and, on a crash,
# the error, the first frames of its stack and the input written. Exit status 1 when any
# target crashed, hung or ran out of memory in this run.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true

need=()
for p in clang libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed' || need+=("$p")
done
if [ ${#need[@]} -gt 0 ]; then
  sudo_cmd=(); [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${need[@]}"
fi

cmake --preset fuzz >/dev/null
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=($(ls tools/fuzz/corpus))
fi
cmake --build --preset fuzz -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

status=0
for t in "${targets[@]}"; do
  work=build/fuzz/corpus/$t
  crashes=build/fuzz/crashes/$t
  log=build/fuzz/logs/$t.log
  mkdir -p "$work" "$crashes" "$(dirname "$log")"
  stamp=$(mktemp)
  echo "== fuzz_$t for ${seconds}s (full output: $log)"
  rc=0
  build/fuzz/tools/fuzz/fuzz_"$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
    -max_len=65536 -print_final_stats=1 -artifact_prefix="$crashes/" \
    "$work" "tools/fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
  # The last status line ("#N DONE cov: ... corp: ... exec/s: ...") and the final stats.
  grep -E '^#[0-9]+' "$log" | tail -n 1 || true
  grep -E '^(Done [0-9]+ runs|stat::)' "$log" || true
  # Artifacts written by this run only: older ones stay until removed, but do not count.
  new=$(find "$crashes" -type f -newer "$stamp" | sort)
  rm -f "$stamp"
  if [ "$rc" -ne 0 ] || [ -n "$new" ]; then
    status=1
    echo "!! fuzz_$t failed (exit status $rc):"
    grep -E -m 6 '^(==[0-9]+== ?ERROR|ERROR:|SUMMARY:|terminate called|  what\(\):|.*runtime error:)' \
      "$log" | sed 's/^/   /' || true
    grep -E '^ +#[0-9]+ 0x[0-9a-f]+ in ' "$log" | grep -v -E ' in (fuzzer::|__sanitizer|__asan|__ubsan|__interceptor|std::|__cxa|__gnu|abort|raise|__pthread|__libc|_start|main )' \
      | head -n 6 | sed 's/^/   /' || true
    grep -E 'Test unit written to' "$log" | sed 's/^/   /' || true
    for f in $new; do
      echo "   artifact: $f"
    done
  fi
done
exit $status
