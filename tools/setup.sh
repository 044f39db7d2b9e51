#!/usr/bin/env bash
# hapto's one set-up script. On a fresh Debian 12 machine (root, apt reachable) it installs
# what is missing, builds, and then:
#   tools/setup.sh main   runs the main job: a two-device simulated session over the
#                         embedded default scene, printing each device's haptic load
#                         (installs and builds only what the `hapto` command needs);
#   tools/setup.sh test   runs the whole test suite through ctest: in the release build, then
#                         under AddressSanitizer + UBSan (asan) and, the tests that start
#                         threads, under ThreadSanitizer (tsan; HAPTO_TEST_SET in CMakeLists.txt),
#                         each sanitizer build overlapping the tests before it (see run_tests).
# Both are idempotent: a second run installs nothing and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-}
case "$mode" in
  main|test) shift ;;
  *) echo "usage: tools/setup.sh main [arguments for hapto run] | test [arguments for ctest]" >&2
     exit 2 ;;
esac

# The main job needs only what the `hapto` command links; the test suite needs the test and
# benchmark libraries, the references (Bullet, FCL, Boost), umockdev for the Falcon's USB tests,
# gnuplot for plots, three.js and Chromium for the view's page, Doxygen for the API reference.
main_packages=(
  build-essential cmake ninja-build pkg-config
  libtbb-dev libglm-dev libeigen3-dev libusb-1.0-0-dev libcli11-dev nlohmann-json3-dev
  libsimdjson-dev libcpp-httplib-dev libmeshoptimizer-dev libqhull-dev
)
test_packages=(
  git catch2 gnuplot-nox libbenchmark-dev libbullet-dev libfcl-dev libboost-dev
  umockdev libumockdev-dev libglib2.0-dev libjs-three chromium python3 doxygen
  python3-dev python3-numpy python3-pytest pybind11-dev python3-matplotlib
)
packages=("${main_packages[@]}")
[ "$mode" = test ] && packages+=("${test_packages[@]}")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=(); [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

jobs=$(nproc)
build() {
  local preset=$1
  cmake --preset "$preset" >/dev/null && cmake --build --preset "$preset" -j "$jobs"
}

# `tools/setup.sh test` is a pipeline over the presets. Release is built first; then a builder
# in the background builds asan and tsan in turn while this shell runs each preset's ctest as
# soon as that preset is built, so a sanitizer build takes the cores the tests before it leave
# idle (the realtime tests mostly wait on the wall clock: in release they used 28 CPU s in
# 121 s). The tests keep the machine: the builder runs under SCHED_IDLE (chrt --idle), so it
# gets a core only when no test wants it and any test thread that wakes takes the core back at
# once; the realtime tests stay alone among tests (RUN_SERIAL). The output is a sequential
# run's: a sanitizer build's output is held and printed whole just before its preset's tests.
# Every preset is built and tested even after a failure; each ctest prints its own failures. A
# preset's failed tests run once more, alone; the run fails if any build failed or any test
# failed twice, and its last lines name every test that failed, with the end of its output.
# Arguments after `test` go to every ctest (e.g. `tools/setup.sh test -R bad_input`).
builder_pid= builder_dir=

# [builder] Builds each preset given, under SCHED_IDLE; DIR/PRESET.log holds its output and
# DIR/PRESET.status its exit status, which appears only once that build has ended.
build_in_background() {
  local dir=$1 preset status
  shift
  chrt --idle -p 0 "$BASHPID" >/dev/null 2>&1 || renice -n 19 -p "$BASHPID" >/dev/null
  for preset in "$@"; do
    status=0
    build "$preset" >"$dir/$preset.log" 2>&1 || status=$?
    echo "$status" >"$dir/$preset.status.tmp"
    mv "$dir/$preset.status.tmp" "$dir/$preset.status"
  done
}

# Waits for the builder to end PRESET's build, prints its output, returns its exit status.
wait_for_build() {
  local preset=$1 start=$SECONDS
  while [ ! -e "$builder_dir/$preset.status" ]; do
    if ! kill -0 "$builder_pid" 2>/dev/null; then
      echo "setup: the background build ended before building $preset" >&2
      return 1
    fi
    sleep 1
  done
  echo "== $preset: build (in the background; waited $((SECONDS - start)) s for its end)"
  cat "$builder_dir/$preset.log"
  return "$(cat "$builder_dir/$preset.status")"
}

run_tests() {
  local preset status=0 failed=()
  echo "== release: build"
  build release || status=$?
  builder_dir=$(mktemp -d "${TMPDIR:-/tmp}/hapto-setup-test.XXXXXX")
  # On any exit the builder's whole process group (ninja, the compilers) goes too.
  trap '[ -z "$builder_pid" ] || kill -TERM -- "-$builder_pid" 2>/dev/null; rm -rf "$builder_dir"' EXIT
  trap 'exit 130' INT TERM
  set -m # the builder gets its own process group
  build_in_background "$builder_dir" asan tsan </dev/null &
  builder_pid=$!
  set +m
  for preset in release asan tsan; do
    if [ "$preset" = release ]; then
      [ "$status" -eq 0 ] || { failed+=("release (build)"); continue; }
    elif ! wait_for_build "$preset"; then
      failed+=("$preset (build)")
      continue
    fi
    echo "== $preset: ctest"
    ctest --preset "$preset" -j "$jobs" "$@" || rerun_failed "$preset" "$@" ||
      failed+=("$preset (tests)")
  done
  wait "$builder_pid" || true
  builder_pid=
  echo "== test: $SECONDS s in all"
  for preset in release asan tsan; do
    print_tests "$preset: failed, then passed on a rerun" "$builder_dir/$preset.first-failed" \
      "$builder_dir/$preset.first-log"
  done
  if [ ${#failed[@]} -gt 0 ]; then
    for preset in release asan tsan; do
      print_tests "$preset: failed" "build/$preset/Testing/Temporary/LastTestsFailed.log" \
        "build/$preset/Testing/Temporary/LastTest.log"
    done
    echo "== FAILED: ${failed[*]}"
    return 1
  fi
}

# After PRESET's ctest failed: runs its failed tests once more, alone (-j 1, so a test that
# failed from the machine's load, e.g. a wall-clock session's servo thread held off past its
# watchdog, gets the machine). Returns whether they all passed. The first run's list and log
# are kept for the summary, which names every test that needed the rerun.
rerun_failed() {
  local preset=$1 dir=build/$1/Testing/Temporary
  shift
  cp "$dir/LastTestsFailed.log" "$builder_dir/$preset.first-failed" 2>/dev/null || return 1
  cp "$dir/LastTest.log" "$builder_dir/$preset.first-log"
  echo "== $preset: ctest, the failed tests again"
  ctest --preset "$preset" -j 1 --rerun-failed "$@"
}

# Repeats, at the end of the run where a log's tail shows it, each test in ctest's list of
# failed tests FAILED (under the heading TITLE), with the last lines of its output from ctest's
# log LOG (ctest printed it whole in its own run above).
print_tests() {
  local title=$1 failed=$2 log=$3
  [ -s "$failed" ] || return 0
  echo "== $title:"
  awk -F: 'NR == FNR { failed[$1] = 1; next }
    /^[0-9]+\/[0-9]+ Test: / { split($0, a, "/"); show = (a[1] in failed); n = 0 }
    show && /^[0-9]+\/[0-9]+ Test: / { print "-- " substr($0, index($0, ": ") + 2) }
    show && /^Output:/ { n = 0; keep = 1; getline; next }
    show && /^<end of output>/ {
      for (i = (n > 30 ? n - 30 : 0); i < n; i++) print "   " line[i]
      keep = 0
    }
    show && keep { line[n++] = $0 }' "$failed" "$log"
}

case "$mode" in
  main)
    # Only the `hapto` command (the main preset: no tests, no benchmarks; build/main).
    build main
    exec build/main/tools/hapto run "$@"
    ;;
  test)
    run_tests "$@"
    ;;
esac
