#!/usr/bin/env bash
# bench/stress.sh [BUILD_DIR]: the write-storm and rebirth-storm figures and a healthy
# drive beside a sick neighbour (silent, late, answering every other request), each side by side
# in one run (bench/stress.py says what is measured). The daemon runs on CPU $SERVER_CPU, the
# simulated drives, the writers, the broker, the Sparkplug peer and dg-loadgen on CPU $LOAD_CPU.
# Environment: ROUNDS (4), DURATION (6 s a phase), WRITERS ("0 1 4"), STORM (1: the write storm),
# REBIRTH (1: the rebirth storm), SICK (1: the sick neighbour), SERVER_CPU (0), LOAD_CPU (1).
set -euo pipefail
B=$(realpath "${1:-build-bench}")
for f in drivegated drivegate dg-loadgen; do
  [[ -x $B/bin/$f ]] || { echo "stress.sh: $B/bin/$f missing (build with -DDRIVEGATE_BENCH=ON)" >&2; exit 2; }
done
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr); server on CPU ${SERVER_CPU:-0}, load on CPU ${LOAD_CPU:-1}"
exec python3 "$(dirname "$(realpath "$0")")/stress.py" "$B/bin"
