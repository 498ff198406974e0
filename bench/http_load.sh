#!/usr/bin/env bash
# bench/http_load.sh [BUILD_DIR]: what serving /metrics and /api/v1/status costs the Modbus side.
#
# Starts ONE drivegated, pinned to CPU $SERVER_CPU, polling the same five simulated drives as
# bench/run.sh (bench/lib.sh), with a Modbus listener and an [http] listener. The load generator,
# the simulators and the scraper run on CPU $LOAD_CPU. Then, for ROUNDS rounds, dg-loadgen at
# N = $CONNS persistent connections (the requests of bench/run.sh: FC03 16..140 alternating with
# FC04 0..18, unit 2) twice: once alone ("without") and once while dg-scraper (bench/scraper.cpp)
# fetches /metrics and /api/v1/status $RATE times a second each ("with"; the scraper starts just
# before the load generator and runs through its warm-up and measured window). The order
# alternates: without first in odd rounds, with first in even ones. Prints the medians of each
# side, the ratio with / without, and the scraper's latencies.
# The scraper shares the load generator's CPU, so its own work (connecting and reading 20 times a
# second: ~0.15 ms of CPU each, most of it the kernel's TCP) can delay the load generator and show
# up in its latencies; it is in C++ for that reason (a Python scraper took 2.5x more). With
# DECOY=1 a third side, "decoy", runs the same scraper with the same pacing and connections
# against two paths the daemon answers with a 10-byte 404: what is left of "with" above "decoy"
# is rendering and sending the pages. The order then rotates over the three sides.
# Environment: ROUNDS (8; even), DURATION (3 s per run), WARMUP (0.5 s), CONNS (8), RATE (10 per
#   path per second), KEEPALIVE (0: a new connection per scrape; 1: one kept open per path),
#   AA (0; 1: the "with" side runs no scraper either, an A/A run of the same comparison),
#   DECOY (0; 1: also the decoy side; make ROUNDS a multiple of 3),
#   SCRAPER_IDLE (0; 1: the scraper runs as SCHED_IDLE, `chrt -i 0`: on the load generator's CPU
#   it then runs only when the load generator does not, and never delays it; the daemon serves
#   the same scrapes),
#   SERVER_CPU (0), LOAD_CPU (1), LARGE (3:16:125), SMALL (4:0:19), UNIT (2),
#   DG_PORT (15070), HTTP_PORT (15071).
set -euo pipefail

B=$(realpath "${1:-build-bench}")
BIN=$B/bin
ROUNDS=${ROUNDS:-8}
DURATION=${DURATION:-3}
WARMUP=${WARMUP:-0.5}
CONNS=${CONNS:-8}
RATE=${RATE:-10}
KEEPALIVE=${KEEPALIVE:-0}
AA=${AA:-0}
DECOY=${DECOY:-0}
SCRAPER_IDLE=${SCRAPER_IDLE:-0}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
LARGE=${LARGE:-3:16:125}
SMALL=${SMALL:-4:0:19}
UNIT=${UNIT:-2}
DG_PORT=${DG_PORT:-15070}
HTTP_PORT=${HTTP_PORT:-15071}
HERE=$(dirname "$(realpath "$0")")

for f in drivegated drivegate dg-loadgen dg-scraper; do
  [[ -e $BIN/$f ]] || { echo "http_load.sh: $BIN/$f missing (build with -DDRIVEGATE_BENCH=ON)" >&2; exit 2; }
done
((ROUNDS % (DECOY ? 3 : 2) == 0)) ||
  echo "http_load.sh: ROUNDS=$ROUNDS: the sides do not go first equally often" >&2

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
# shellcheck source=bench/lib.sh
source "$HERE/lib.sh"
bench_workdir http

start_gateway "$BIN" dg "[server]
listen = \"127.0.0.1:$DG_PORT\"
max_clients = 256

[http]
listen = \"127.0.0.1:$HTTP_PORT\""
DG_PID=$GATEWAY_PID

wait_for_port "$DG_PORT" || { cat "$W"/dg/drivegated.log >&2; exit 1; }
wait_for_port "$HTTP_PORT" || { cat "$W"/dg/drivegated.log >&2; exit 1; }
kill -0 "$DG_PID" 2>/dev/null || { echo "http_load.sh: drivegated did not start (a port taken?)" >&2; cat "$W"/dg/drivegated.log >&2; exit 1; }
python3 "$HERE/mbwrite.py" --wait-online "$DG_PORT" "${START[@]}"
sleep 2

SCRAPE_ARGS=()
((KEEPALIVE)) && SCRAPE_ARGS=(--keep-alive)
# One scrape of each path first: the scraper works, and the sizes are known before the rounds.
taskset -c "$LOAD_CPU" "$BIN/dg-scraper" "$HTTP_PORT" 2 0.5 "$W/probe.txt"
echo "# probe: $(cat "$W/probe.txt")" >>"$W/results.txt"

failed() {
  echo "http_load.sh: dg-loadgen failed ($1):" >&2
  tail -5 "$W/loadgen.err" >&2
  kill -0 "$DG_PID" 2>/dev/null || echo "http_load.sh: drivegated (pid $DG_PID) is gone" >&2
  tail -5 "$W/dg/drivegated.log" >&2
  exit 1
}

load() {  # load SIDE N ROUND
  local out scraper=
  if [[ $1 != without ]] && ((!AA)); then
    local extra=()
    [[ $1 == decoy ]] && extra=(--decoy)
    : >"$W/scrape.txt"
    local sched=()
    ((SCRAPER_IDLE)) && sched=(chrt -i 0)
    "${sched[@]}" taskset -c "$LOAD_CPU" "$BIN/dg-scraper" "$HTTP_PORT" "$RATE" \
      "$(python3 -c "print($WARMUP + $DURATION + 0.5)")" "$W/scrape.txt" "${SCRAPE_ARGS[@]}" \
      "${extra[@]}" 2>>"$W/scraper.err" &
    scraper=$!
    sleep 0.2  # the scraper's start-up, outside the load generator's window
  fi
  out=$(taskset -c "$LOAD_CPU" "$BIN/dg-loadgen" --port "$DG_PORT" --pid "$DG_PID" \
    --connections "$2" --duration "$DURATION" --warmup "$WARMUP" --unit "$UNIT" \
    --large "$LARGE" --small "$SMALL" 2>>"$W/loadgen.err") || failed "$1 N=$2"
  echo "modbus $1 $2 $3 $out" | tee -a "$W/results.txt" >&2
  if [[ -n $scraper ]]; then
    wait "$scraper" || true
    echo "$(cat "$W/scrape.txt") side=$1 round=$3" | tee -a "$W/results.txt" >&2
  fi
}

SIDES=(without with)
((DECOY)) && SIDES=(without with decoy)
for round in $(seq "$ROUNDS"); do
  for n in $CONNS; do
    # Round r starts with side (r - 1) mod sides: without, with[, decoy], without, ...
    for k in $(seq 0 $((${#SIDES[@]} - 1))); do
      load "${SIDES[$(((round - 1 + k) % ${#SIDES[@]}))]}" "$n" "$round"
    done
  done
done

echo
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr), $(python3 --version); server on CPU $SERVER_CPU, load generator, simulators and" \
  "scraper on CPU $LOAD_CPU; $ROUNDS rounds x ${DURATION}s; large=$LARGE small=$SMALL unit=$UNIT;" \
  "scrape rate $RATE/s per path, keep-alive $KEEPALIVE, decoy $DECOY, scraper SCHED_IDLE $SCRAPER_IDLE$( ((AA)) && echo '; A/A: no scraper on either side')"
python3 "$HERE/http_summary.py" "$W/results.txt"
if [[ -s $W/scraper.err ]]; then echo "scraper errors:"; sort "$W/scraper.err" | uniq -c | head -5; fi
grep -i "error\|critical\|warn" "$W"/dg/drivegated.log | head -5 || true
