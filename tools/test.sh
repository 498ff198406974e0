#!/bin/sh
# Builds drivegate and runs every test: codecs, drivers, the core, the Modbus server and the
# end-to-end tests of the real daemon with simulated drives on pseudo-terminals.
# Installs what the tests use first (tools/deps.sh test: GoogleTest, chromium, prometheus, tshark,
# mosquitto, ser2net, pymodbus, Node.js and the Sparkplug peer's npm packages).
# Extra arguments go to cmake (e.g. -DDRIVEGATE_SANITIZE=address,undefined with BUILD_DIR=...);
# CTEST_ARGS go to ctest (e.g. CTEST_ARGS="-E ^StatusPage" to leave some out).
set -eu
cd "$(dirname "$0")/.."
# The tests on, whatever an earlier tools/demo.sh configured in this build tree.
DEPS="test" tools/build.sh -DDRIVEGATE_TESTS=ON "$@"
# shellcheck disable=SC2086 # CTEST_ARGS is a list of arguments
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j"$(nproc)" --timeout 300 ${CTEST_ARGS:-}
