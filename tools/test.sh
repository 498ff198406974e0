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
# shellcheck disable=SC2086 # CTEST_ARGS is a list of arguments
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j"$(nproc)" --timeout 300 ${CTEST_ARGS:-}
