#!/bin/sh
# Builds drivegate and runs every test: codecs, drivers, the core, the Modbus server and the
# end-to-end tests of the real daemon with simulated drives on pseudo-terminals.
# Extra arguments go to cmake (e.g. -DDRIVEGATE_SANITIZE=address,undefined with BUILD_DIR=...);
# CTEST_ARGS go to ctest (e.g. CTEST_ARGS="-E ^StatusPage" to leave some out).
set -eu
cd "$(dirname "$0")/.."
tools/build.sh "$@"
# shellcheck disable=SC2086 # CTEST_ARGS is a list of arguments
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j"$(nproc)" --timeout 300 ${CTEST_ARGS:-}
