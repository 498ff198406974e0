#!/bin/sh
# Builds every libFuzzer target (tests/fuzz) in build-fuzz with clang-14 under ASan + UBSan and
# runs each for a bounded time, starting from its seed corpus and crash regressions.
#
#   tools/fuzz.sh [SECONDS_PER_TARGET]     default 60; CI: tools/fuzz.sh 60
#
# Exits non-zero when a build fails or a target crashes, leaks or times out; the crashing input is
# left in build-fuzz/fuzz/artifacts/<target>/. To keep it as a regression test, copy it to
# tests/fuzz/regressions/<target>/ (the replay tests feed every file there).
# Environment: FUZZ_JOBS (build parallelism, default 2), FUZZ_BUILD_DIR (default build-fuzz).
set -eu

seconds=${1:-60}
root=$(cd "$(dirname "$0")/.." && pwd)
build=${FUZZ_BUILD_DIR:-$root/build-fuzz}
jobs=${FUZZ_JOBS:-2}

command -v clang++-14 >/dev/null || {
  echo "fuzz.sh: clang++-14 not found (apt-get install clang-14 libclang-rt-14-dev)" >&2
  exit 2
}

# Everything is instrumented for coverage (fuzzer-no-link) and sanitized, plugins included; only
# the fuzz_* executables link libFuzzer's main. The adapters' plugins and the e2e programs are not
# needed here, so the tests and the daemon's own programs are left to the other build trees.
cmake -S "$root" -B "$build" \
  -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link" \
  -DDRIVEGATE_SANITIZE=address,undefined \
  -DDRIVEGATE_FUZZ=ON \
  -DDRIVEGATE_TESTS=OFF >"$build.cmake.log" 2>&1 || {
  cat "$build.cmake.log" >&2
  exit 2
}

targets=$(cat "$build/fuzz/targets.txt")
build_targets=""
for t in $targets; do build_targets="$build_targets fuzz_$t"; done
# shellcheck disable=SC2086
cmake --build "$build" -j"$jobs" --target $build_targets

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

failed=""
for t in $targets; do
  work="$build/fuzz/corpus/$t"        # grows between runs; the checked-in seeds stay as they are
  artifacts="$build/fuzz/artifacts/$t/"
  mkdir -p "$work" "$artifacts"
  seeds="$root/tests/fuzz/corpus/$t"
  regressions="$root/tests/fuzz/regressions/$t"
  dirs="$work"
  [ -d "$seeds" ] && dirs="$dirs $seeds"
  [ -d "$regressions" ] && dirs="$dirs $regressions"
  dict="$root/tests/fuzz/dict/$t.dict"
  dict_opt=""
  [ -f "$dict" ] && dict_opt="-dict=$dict"
  echo "fuzz.sh: $t for ${seconds}s"
  # -timeout: one input taking over 10 s is a hang; -rss_limit_mb: ASan's default 2 GB budget.
  # shellcheck disable=SC2086
  if ! "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=4096 -print_final_stats=1 -artifact_prefix="$artifacts" $dict_opt $dirs \
      >"$build/fuzz/$t.log" 2>&1; then
    echo "fuzz.sh: $t FAILED (log: $build/fuzz/$t.log, input in $artifacts)" >&2
    tail -n 60 "$build/fuzz/$t.log" >&2
    failed="$failed $t"
  else
    grep -E "stat::number_of_executed_units|cov:" "$build/fuzz/$t.log" | tail -n 2
  fi
done

if [ -n "$failed" ]; then
  echo "fuzz.sh: crashed:$failed" >&2
  exit 1
fi
echo "fuzz.sh: every target ran ${seconds}s without a crash"
