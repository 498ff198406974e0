#!/usr/bin/env bash
# bench/run.sh [BUILD_DIR]: the Modbus TCP benchmark, in one command.
#
# Starts a simulated drive for each of the five adapters (`drivegate sim` on ptys), drivegated
# polling them, and the bare libmodbus server (dg-baseline). Both servers are pinned to CPU
# $SERVER_CPU, the load generator and the simulators to CPU $LOAD_CPU. Then, for ROUNDS rounds,
# for N in $CONNS, runs dg-loadgen against the baseline and against drivegate (alternating which
# goes first), and prints the median of every figure for each side and the ratio drivegate / baseline.
# Then the independence check: the ed3100 drive goes silent (times out on every poll) while fdc1
# keeps streaming, and drivegate is measured again at N = 1 and 8.
#
# Both sides get the same request stream (see docs/performance.md):
#   large: FC03 holding registers 16..140 (125 registers: the ed3100's 125 parameters, unit 2)
#   small: FC04 input registers 0..18 (the common block, unit 2)
# Environment: ROUNDS (4; even, so each side goes first equally often), DURATION (3 s per run),
#   WARMUP (0.5 s), CONNS ("1 8 64"), SERVER_CPU (0), LOAD_CPU (1), LARGE (3:16:125),
#   SMALL (4:0:19), UNIT (2).
#   AGAINST=OTHER_BUILD_DIR: the baseline side is that build's drivegated (with five simulated
#   drives of its own) instead of dg-baseline: a change to drivegate measured side by side
#   against the build before it. (Its independence figures then include the second daemon's
#   polling on the same CPU, so they are not the published ones.)
set -euo pipefail

B=$(realpath "${1:-build-bench}")
BIN=$B/bin
ROUNDS=${ROUNDS:-4}
DURATION=${DURATION:-3}
WARMUP=${WARMUP:-0.5}
CONNS=${CONNS:-"1 8 64"}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
LARGE=${LARGE:-3:16:125}
SMALL=${SMALL:-4:0:19}
UNIT=${UNIT:-2}
DG_PORT=${DG_PORT:-15020}
BASE_PORT=${BASE_PORT:-15030}
HERE=$(dirname "$(realpath "$0")")
AGAINST=${AGAINST:-}
AGAINST_BIN=

need() {  # need FILE WHAT
  [[ -e $1 ]] || { echo "run.sh: $1 missing ($2)" >&2; exit 2; }
}
need "$BIN/drivegated" "build with -DDRIVEGATE_BENCH=ON"
need "$BIN/drivegate" "build with -DDRIVEGATE_BENCH=ON"
need "$BIN/dg-loadgen" "build with -DDRIVEGATE_BENCH=ON"
if [[ -n $AGAINST ]]; then
  AGAINST_BIN=$(realpath "$AGAINST")/bin
  need "$AGAINST_BIN/drivegated" "AGAINST must be a build directory"
  need "$AGAINST_BIN/drivegate" "AGAINST must be a build directory"
  need "$AGAINST_BIN/../adapters" "AGAINST must be a build directory"
else
  need "$BIN/dg-baseline" "build with -DDRIVEGATE_BENCH=ON"
fi
((ROUNDS % 2 == 0)) || echo "run.sh: ROUNDS=$ROUNDS is odd: the baseline goes first once more" >&2

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir bench

# shellcheck source=bench/lib.sh
source "$HERE/lib.sh"

# server_toml PORT: the [server] table of both gateways.
server_toml() {
  printf '[server]\nlisten = "127.0.0.1:%s"\nmax_clients = 256' "$1"
}

start_gateway "$BIN" dg "$(server_toml "$DG_PORT")"
DG_PID=$GATEWAY_PID
if [[ -n $AGAINST ]]; then
  start_gateway "$AGAINST_BIN" base "$(server_toml "$BASE_PORT")"
else
  taskset -c "$SERVER_CPU" "$BIN/dg-baseline" --port "$BASE_PORT" >"$W/baseline.log" 2>&1 &
  GATEWAY_PID=$!
  PIDS+=("$GATEWAY_PID")
fi
BASE_PID=$GATEWAY_PID

wait_port() {
  wait_for_port "$1" && return 0
  cat "$W"/*/drivegated.log >&2
  exit 1
}
wait_port "$DG_PORT"
wait_port "$BASE_PORT"
# Start every drive (START: bench/lib.sh).
python3 "$HERE/mbwrite.py" --wait-online "$DG_PORT" "${START[@]}"
[[ -n $AGAINST ]] && python3 "$HERE/mbwrite.py" --wait-online "$BASE_PORT" "${START[@]}"
sleep 2

load() {  # load SIDE PORT PID N ROUND TAG
  local out
  out=$(taskset -c "$LOAD_CPU" "$BIN/dg-loadgen" --port "$2" --pid "$3" --connections "$4" \
    --duration "$DURATION" --warmup "$WARMUP" --unit "$UNIT" --large "$LARGE" --small "$SMALL")
  echo "$6 $1 $4 $5 $out" | tee -a "$W/results.txt" >&2
}

# The side measured second gains a few per cent (an A/A run of one binary against itself showed
# it: docs/performance.md), so the order alternates: baseline first in odd rounds, drivegate
# first in even ones.
for round in $(seq "$ROUNDS"); do
  for n in $CONNS; do
    if ((round % 2 == 1)); then
      load baseline "$BASE_PORT" "$BASE_PID" "$n" "$round" tcp
      load drivegate "$DG_PORT" "$DG_PID" "$n" "$round" tcp
    else
      load drivegate "$DG_PORT" "$DG_PID" "$n" "$round" tcp
      load baseline "$BASE_PORT" "$BASE_PID" "$n" "$round" tcp
    fi
  done
done

# Independence: ed3100 times out on every poll, fdc1 streams, the others are polled.
echo "silent on" >&"${SIM_IN[dg/ed3100]}"
sleep 2
for round in $(seq "$ROUNDS"); do
  for n in 1 8; do
    load drivegate "$DG_PORT" "$DG_PID" "$n" "$round" silent
  done
done
python3 "$HERE/mbwrite.py" --read-timeouts "$DG_PORT" 2 >>"$W/results.txt"

echo
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr); server on CPU $SERVER_CPU, load generator on CPU $LOAD_CPU;" \
  "$ROUNDS rounds x ${DURATION}s; large=$LARGE small=$SMALL unit=$UNIT"
[[ -n $AGAINST ]] && echo "# baseline side: drivegated of $AGAINST" >>"$W/results.txt"
python3 "$HERE/summarize.py" "$W/results.txt"
grep -i "error\|critical" "$W"/*/drivegated.log | head -5 || true
