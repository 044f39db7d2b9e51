#!/usr/bin/env bash
# Runs every libFuzzer target for a bounded time (default 60 s each).
#   tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
# Builds the `fuzz` preset (clang, ASan + UBSan + libFuzzer) into build/fuzz. Each target
# starts from its committed seed corpus tools/fuzz/corpus/<name>/ and grows a scratch corpus
# in build/fuzz/corpus/<name>/. Crashes land in build/fuzz/crashes/<name>/; fix the bug, then
# copy the crash input into tools/fuzz/corpus/<name>/ so the ctest replay keeps it fixed.
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
  mkdir -p "$work" "$crashes"
  echo "== fuzz_$t for ${seconds}s"
  if ! build/fuzz/tools/fuzz/fuzz_"$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
        -max_len=65536 -print_final_stats=1 -artifact_prefix="$crashes/" \
        "$work" "tools/fuzz/corpus/$t" 2>&1 | tail -n 12; then
    status=1
  fi
  if [ -n "$(ls -A "$crashes")" ]; then
    echo "!! fuzz_$t found crashes in $crashes"
    status=1
  fi
done
exit $status
