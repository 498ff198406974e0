#!/bin/sh
# Builds drivegate and runs every test: codecs, drivers, the core, the Modbus server and the
# end-to-end tests of the real daemon with simulated drives on pseudo-terminals.
# Installs what the tests use first (tools/deps.sh test: GoogleTest, chromium, prometheus, tshark,
# mosquitto, ser2net, pymodbus, Node.js and the Sparkplug peer's npm packages).
# Extra arguments go to cmake (e.g. -DDRIVEGATE_SANITIZE=address,undefined with BUILD_DIR=...);
# CTEST_ARGS go to ctest (e.g. CTEST_ARGS="-E ^StatusPage" to leave some out).
set -eu
cd "$(dirname "$0")/.."
# The tests on, whatever an earlier tools/demo.sh configured in this build tree. Optimised as the
# package is (-O2), with line tables only for debug information (-g1: a failing test's backtrace
# still names file and line; a test TU compiles about a quarter faster than with full -g, which
# keeps CI's two-core run under its hour). `cmake -B build -DCMAKE_CXX_FLAGS_RELWITHDEBINFO=...`
# sets it back for a debugging session.
DEPS="test" tools/build.sh -DDRIVEGATE_TESTS=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" "$@"
# Two runs: the tests that compute, one per core; then those labelled `waits` (the end-to-end
# tests of the real daemon, tests/CMakeLists.txt), two per core: each spends most of its time
# waiting on the wall clock (40 of them took 7 CPU seconds in 85 s), so two cores' worth of
# them at once leaves the CPU mostly idle. Both run whatever the first's result; the exit status
# is a failure if either failed.
build=${BUILD_DIR:-build}
jobs=$(nproc)
status=0
# shellcheck disable=SC2086 # CTEST_ARGS is a list of arguments
ctest --test-dir "$build" --output-on-failure -j"$jobs" --timeout 300 -LE waits ${CTEST_ARGS:-} ||
  status=$?
# shellcheck disable=SC2086
ctest --test-dir "$build" --output-on-failure -j"$((2 * jobs))" --timeout 300 -L waits \
  ${CTEST_ARGS:-} || status=$?
exit "$status"
