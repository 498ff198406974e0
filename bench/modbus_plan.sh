#!/usr/bin/env bash
# bench/modbus_plan.sh [BUILD_DIR] [-- ARGS...]: Modbus read plans against the wire's minimum.
#
# Builds dg-modbus-plan in BUILD_DIR (configured with -DDRIVEGATE_BENCH=ON -DDRIVEGATE_TESTS=ON:
# it runs the tests' bus rig) and runs it: for each shipped profile of the modbus adapter and a
# synthetic larger one, one full poll cycle on simulated time (the real bus engine and driver
# against the adapter's simulator), read by the profile's plan and one request per point, beside
# the floor the wire allows and the best plan the device's limits allow, at 19200 and 9600 baud
# 8E1. Simulated time: the numbers are exact, the same on every machine, and take no wall time.
# ARGS go to dg-modbus-plan (--baud N, --profile NAME_OR_PATH, --turnaround exact|whole-ms,
# --check).
#
# BASE=DIR: side by side with another tree's build (a worktree of main, configured the same way):
# its dg-modbus-plan (the rig's slave answering after whole milliseconds, as that tree's rig
# does), this tree's with --turnaround whole-ms (the same slave: what the engine alone changed)
# and this tree's as it is, over the same profiles (this tree's shipped folder and the synthetic
# one), each table in full and then joined (bench/modbus_plan_compare.py).
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
if [[ -z ${BASE:-} ]]; then
  exec "$B/bin/dg-modbus-plan" "$@"
fi
BASE=$(realpath "$BASE")
cmake --build "$BASE" -j"${JOBS:-2}" --target dg-modbus-plan >"$BASE/modbus_plan.build.log" 2>&1 ||
  { tail -20 "$BASE/modbus_plan.build.log" >&2; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
# The base's own list (its shipped profiles and the synthetic one), then each profile of this tree
# on its own (a profile the base cannot read costs only its own rows).
echo "== base ($BASE): its engine and rig"
{
  "$BASE/bin/dg-modbus-plan" "$@" || true
  for p in "$HERE"/../adapters/modbus/profiles/*.toml; do
    "$BASE/bin/dg-modbus-plan" --profile "$(realpath "$p")" "$@" | grep '^| ' | tail -n +3 || true
  done
} | tee "$W/base"
echo "== this tree, the base's rig (--turnaround whole-ms)"
"$B/bin/dg-modbus-plan" --turnaround whole-ms "$@" | tee "$W/whole" || true
echo "== this tree"
"$B/bin/dg-modbus-plan" "$@" | tee "$W/exact" || true
echo "== joined"
python3 "$HERE/modbus_plan_compare.py" base="$W/base" this-whole-ms="$W/whole" this="$W/exact"
