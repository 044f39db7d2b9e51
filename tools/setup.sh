#!/usr/bin/env bash
# hapto's one set-up script. On a fresh Debian 12 machine (root, apt reachable) it installs
# what is missing, builds, and then:
#   tools/setup.sh main   runs the main job: a two-device simulated session over the
#                         embedded default scene, printing each device's haptic load
#                         (installs and builds only what the `hapto` command needs);
#   tools/setup.sh test   runs the whole test suite through ctest: in the release build, then
#                         under AddressSanitizer + UBSan (asan) and ThreadSanitizer (tsan).
# Both are idempotent: a second run installs nothing and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-}
case "$mode" in
  main|test) shift ;;
  *) echo "usage: tools/setup.sh main|test [extra arguments for hapto run]" >&2; exit 2 ;;
esac

# The main job needs only what the `hapto` command links; the test suite needs the test and
# benchmark libraries, the references (Bullet, FCL, Boost), umockdev for the Falcon's USB tests,
# gnuplot for plots, three.js and Chromium for the view's page, Doxygen for the API reference.
main_packages=(
  build-essential cmake ninja-build pkg-config
  libtbb-dev libglm-dev libeigen3-dev libusb-1.0-0-dev libcli11-dev nlohmann-json3-dev
  libsimdjson-dev libcpp-httplib-dev libmeshoptimizer-dev
)
test_packages=(
  git catch2 gnuplot-nox libbenchmark-dev libbullet-dev libfcl-dev libboost-dev
  umockdev libumockdev-dev libglib2.0-dev libjs-three chromium python3 doxygen
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
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset" -j "$jobs"
}

case "$mode" in
  main)
    # Only the `hapto` command (the main preset: no tests, no benchmarks; build/main).
    build main
    exec build/main/tools/hapto run "$@"
    ;;
  test)
    for preset in release asan tsan; do
      echo "== $preset: build"
      build "$preset"
      echo "== $preset: ctest"
      ctest --preset "$preset" -j "$jobs"
    done
    ;;
esac
