#!/bin/sh
# Builds every libFuzzer target (tests/fuzz) in build-fuzz with clang-14 under ASan + UBSan and
# runs each for a bounded time, starting from its seed corpus and crash regressions.
#
#   tools/fuzz.sh [SECONDS_PER_TARGET]     default 60; CI: tools/fuzz.sh 60
#
# Exits non-zero when a build fails or a target crashes, leaks or times out; the crashing input is
# left in build-fuzz/fuzz/artifacts/<target>/. To keep it as a regression test, copy it to the
# target's regressions folder (the replay tests feed every file there): tests/fuzz/regressions/
# <target>/ for the core's targets, adapters/<id>/fuzz/regressions/ for adapter_<id>; the seed
# corpora are beside them (tests/fuzz/corpus/<target>/, adapters/<id>/fuzz/corpus/), and
# build-fuzz/fuzz/targets.txt (written by tests/fuzz/CMakeLists.txt) says which is whose.
# Environment: FUZZ_JOBS (build parallelism, default 2), FUZZ_BUILD_DIR (default build-fuzz),
# FUZZ_TARGETS (only these targets, by name, space-separated: FUZZ_TARGETS=adapter_ed3100).
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
# Warnings are errors in the GCC builds (the tests' and the sanitizers'); here clang-14's own
# warnings are shown, not fatal: this build is for finding crashes.
# -O1 with line tables only, as OSS-Fuzz builds: a crash's stack still names file and line, and
# a source compiles about an eighth faster than with -O2 -g (gateway/device_writes.cpp under
# clang-14 with the sanitizers: 14.9 s against 17.1 s of CPU). Sources compile in unity batches,
# as in CI's sanitizer pass (.ci/run says why and what it saves).
cmake -S "$root" -B "$build" \
  -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link" \
  -DDRIVEGATE_SANITIZE=address,undefined \
  -DDRIVEGATE_FUZZ=ON \
  -DCMAKE_UNITY_BUILD=ON \
  -DDRIVEGATE_WERROR=OFF \
  -DDRIVEGATE_TESTS=OFF >"$build.cmake.log" 2>&1 || {
  cat "$build.cmake.log" >&2
  exit 2
}

# targets.txt: one target a line, tab-separated: name, seed corpus, regressions, dictionary.
list="$build/fuzz/targets.txt"
targets=""
while IFS="$(printf '\t')" read -r t _; do
  case " ${FUZZ_TARGETS:-$t} " in *" $t "*) targets="$targets $t" ;; esac
done <"$list"
[ -n "$targets" ] || {
  echo "fuzz.sh: no target (FUZZ_TARGETS=${FUZZ_TARGETS:-}; $list)" >&2
  exit 2
}
build_targets=""
for t in $targets; do build_targets="$build_targets fuzz_$t"; done
# shellcheck disable=SC2086
cmake --build "$build" -j"$jobs" --target $build_targets

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

failed=""
tab="$(printf '\t')"
while IFS="$tab" read -r t seeds regressions dict; do
  case " $targets " in *" $t "*) ;; *) continue ;; esac
  work="$build/fuzz/corpus/$t"        # grows between runs; the checked-in seeds stay as they are
  artifacts="$build/fuzz/artifacts/$t/"
  mkdir -p "$work" "$artifacts"
  dirs="$work"
  [ -d "$seeds" ] && dirs="$dirs $seeds"
  [ -d "$regressions" ] && dirs="$dirs $regressions"
  dict_opt=""
  [ -f "$dict" ] && dict_opt="-dict=$dict"
  echo "fuzz.sh: $t for ${seconds}s"
  # -timeout: one input taking over 10 s is a hang; -rss_limit_mb: ASan's default 2 GB budget.
  # shellcheck disable=SC2086
  if ! "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=4096 -print_final_stats=1 -artifact_prefix="$artifacts" $dict_opt $dirs \
      </dev/null >"$build/fuzz/$t.log" 2>&1; then
    echo "fuzz.sh: $t FAILED (log: $build/fuzz/$t.log, input in $artifacts)" >&2
    tail -n 60 "$build/fuzz/$t.log" >&2
    failed="$failed $t"
  else
    grep -E "stat::number_of_executed_units|cov:" "$build/fuzz/$t.log" | tail -n 2
  fi
done <"$list"

if [ -n "$failed" ]; then
  echo "fuzz.sh: crashed:$failed" >&2
  exit 1
fi
echo "fuzz.sh: every target ran ${seconds}s without a crash"
