#!/usr/bin/env bash
# bench/framed.sh [BUILD_DIR] [-- ARGS...]: the described protocols beside the C++ adapters.
#
# Builds dg-framed-bench in BUILD_DIR (configured with -DDRIVEGATE_BENCH=ON -DDRIVEGATE_TESTS=ON:
# it runs the tests' bus rig) and runs it: for nidec-washer, mdriver-2400 and fdc1, the bus time of
# a poll cycle on simulated time (exact, the same on every machine) under the C++ adapter and under
# framed with the shipped description, against the same simulator; then the codecs' CPU per frame,
# side by side on this machine. ARGS go to dg-framed-bench (--check, --frames N).
set -euo pipefail
HERE=$(dirname "$(realpath "$0")")
B=$(realpath "${1:-build-bench}")
shift || true
[[ ${1:-} == -- ]] && shift
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(dirname "$HERE")}
if ! cmake --build "$B" -j"${JOBS:-2}" --target dg-framed-bench >"$B/framed.build.log" 2>&1; then
  tail -20 "$B/framed.build.log" >&2
  echo "${0##*/}: could not build dg-framed-bench in $B (configure it with" \
    "-DDRIVEGATE_BENCH=ON -DDRIVEGATE_TESTS=ON)" >&2
  exit 1
fi
exec "$B/bin/dg-framed-bench" "$@"
