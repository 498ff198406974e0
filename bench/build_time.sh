#!/usr/bin/env bash
# bench/build_time.sh [OUT_DIR]: how long the package's programs take to compile, one source
# file at a time against unity batches (CMAKE_UNITY_BUILD), in one run, one after the other.
#
# The programs the Debian package ships (drivegated, drivegate, the adapter plugins; no tests),
# with the package's own compiler flags (dpkg-buildflags with hardening=+all, as
# packaging/debian/rules asks), each way in a fresh build tree under OUT_DIR (default
# build-time/), ccache off, with `nproc` jobs. Prints the wall time of each build and their
# ratio. Noisy machines: run it when nothing else builds; the ratio is what to trust.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-build-time}")
mkdir -p "$out"
jobs=$(nproc)
export CCACHE_DISABLE=1
export DEB_BUILD_MAINT_OPTIONS=hardening=+all
cxxflags=$(dpkg-buildflags --get CXXFLAGS)
cppflags=$(dpkg-buildflags --get CPPFLAGS)
ldflags=$(dpkg-buildflags --get LDFLAGS)
declare -A took
for mode in per-file unity; do
  tree="$out/$mode"
  rm -rf "$tree"
  unity=OFF
  [ "$mode" = unity ] && unity=ON
  cmake -S . -B "$tree" -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="$cppflags $cxxflags" \
    -DCMAKE_EXE_LINKER_FLAGS="$ldflags" -DCMAKE_SHARED_LINKER_FLAGS="$ldflags" \
    -DCMAKE_MODULE_LINKER_FLAGS="$ldflags" -DDRIVEGATE_TESTS=OFF -DDRIVEGATE_WERROR=OFF \
    -DCMAKE_UNITY_BUILD=$unity >"$tree.configure.log"
  start=$(date +%s.%N)
  cmake --build "$tree" -j"$jobs" >"$tree.build.log" 2>&1
  took[$mode]=$(echo "$(date +%s.%N) - $start" | bc)
  printf '%-8s %7.1f s  (%s)\n' "$mode" "${took[$mode]}" "$tree.build.log"
done
printf 'unity / per-file: %.3f\n' "$(echo "${took[unity]} / ${took[per-file]}" | bc -l)"
