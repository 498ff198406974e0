#!/usr/bin/env bash
# bench/modbus_plan.sh [BUILD_DIR] [-- ARGS...]: Modbus read plans against the wire's minimum.
#
# Builds dg-modbus-plan in BUILD_DIR (configured with -DDRIVEGATE_BENCH=ON -DDRIVEGATE_TESTS=ON:
# it runs the tests' bus rig) and runs it: for each shipped profile of the modbus adapter and a
# synthetic larger one, one full poll cycle on simulated time (the real bus engine and driver
# against the adapter's simulator), read by the profile's plan and one request per point, beside
# the floor the wire allows and the best plan the device's limits allow, at 19200 and 9600 baud
# 8E1. Simulated time: the numbers are exact, the same on every machine, and take no wall time.
# ARGS go to dg-modbus-plan (--baud N, --profile NAME_OR_PATH, --check).
set -euo pipefail
HERE=$(dirname "$(realpath "$0")")
B=$(realpath "${1:-build-bench}")
shift || true
[[ ${1:-} == -- ]] && shift
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(dirname "$HERE")}
if ! cmake --build "$B" -j"${JOBS:-2}" --target dg-modbus-plan >"$B/modbus_plan.build.log" 2>&1; then
  tail -20 "$B/modbus_plan.build.log" >&2
  echo "${0##*/}: could not build dg-modbus-plan in $B (configure it with" \
    "-DDRIVEGATE_BENCH=ON -DDRIVEGATE_TESTS=ON)" >&2
  exit 1
fi
exec "$B/bin/dg-modbus-plan" "$@"
