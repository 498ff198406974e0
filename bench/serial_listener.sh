#!/usr/bin/env bash
# bench/serial_listener.sh [BUILD_DIR]: the serial listener's figure. drivegated as a Modbus RTU slave on a
# serial listener, driven by a master that makes a pty behave like the wire
# (bench/serial_listener_bench.cpp, dg-serial-listener-bench): requests per second against the
# wire's limit for the same request and reply lengths, and the reply gap after the request.
#
# Starts one socat pty pair (`pty,raw,echo=0` both ends: the master's end A, the listener's end
# B), one simulated nidec-washer (`drivegate sim`, on its own pty) and, for each baud in $BAUDS, a
# fresh drivegated whose serial listener has that baud (a TCP listener first, as the end-to-end
# tests configure it; nothing uses it here), polling the drive as unit 1. The master first waits
# for unit 1 to be online (FC04 over the line), then sends COUNT FC03 requests (holding registers
# ADDR.. ADDR+QTY-1: 8 bytes; reply 5 + 2 x QTY bytes), each byte a character time apart (11-bit
# characters, 8E1), and keeps the reply's wire time and the 3.5-character silence before the
# next. Before the daemon runs, `--probe` measures the pty pair's own latency through socat, and
# `--frames` how many request frames the transport alone would make look cut (the framer's
# 1.5-character rule, applied by a SCHED_OTHER reader on the daemon's CPU).
# drivegated, socat and the simulator run on CPU $SERVER_CPU, the master on CPU $LOAD_CPU.
# Environment: BAUDS ("19200 115200"), COUNT_19200 (500), COUNT_115200 (2000), ROUNDS (1: each
#   round runs every baud once), QTY (3), ADDR (0), SERVER_CPU (0), LOAD_CPU (1), PORT (15090:
#   the TCP listener), HTTP_PORT (15091: [http], for the listener's counters), TIMEOUT_MS (100: the
#   master's response timeout), RT (1: the master under SCHED_FIFO 10 when chrt allows it),
#   RX_LATENCY_MS ("": the listener's rx_latency_ms, where the build has that key), DAEMON_RT
#   (0; 1: a diagnosis, below), KEEP_DIR (a directory: each run's gaps, master log and daemon log
#   are copied there).
# "ratio" is over the whole run (an unanswered request costs the response timeout and a 50 ms
# resync); "ratio answered" over the answered transactions alone.
set -euo pipefail
B=$(realpath "${1:-build-bench}")
BIN=$B/bin
PLUGINS=$B/adapters
HERE=$(dirname "$(realpath "$0")")
BAUDS=${BAUDS:-"19200 115200"}
ROUNDS=${ROUNDS:-1}
QTY=${QTY:-3}
ADDR=${ADDR:-0}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
PORT=${PORT:-15090}
HTTP_PORT=${HTTP_PORT:-15091}
KEEP_DIR=${KEEP_DIR:-}
RT=${RT:-1}
RX_LATENCY_MS=${RX_LATENCY_MS:-}
TIMEOUT_MS=${TIMEOUT_MS:-100}
# The master stands in for a UART: it must not be preempted mid-request (a byte late by 1.5
# characters cuts the frame, and the daemon is right to drop it). SCHED_FIFO when allowed.
MASTER=(taskset -c "$LOAD_CPU")
if ((RT)) && chrt -f 10 true 2>/dev/null; then MASTER=(chrt -f 10 "${MASTER[@]}"); fi
# DAEMON_RT=1 (a diagnosis, not the published setting): drivegated and socat under SCHED_FIFO 5
# too, so that nothing else on their CPU delays them.
DAEMON_RT=${DAEMON_RT:-0}
SERVER=(taskset -c "$SERVER_CPU")
((DAEMON_RT)) && SERVER=(chrt -f 5 "${SERVER[@]}")

for f in drivegated drivegate dg-serial-listener-bench; do
  [[ -x $BIN/$f ]] || { echo "serial_listener.sh: $BIN/$f missing (build with -DDRIVEGATE_BENCH=ON)" >&2; exit 2; }
done
command -v socat >/dev/null || { echo "serial_listener.sh: socat missing" >&2; exit 2; }

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir serlis

"${SERVER[@]}" socat "pty,raw,echo=0,link=$W/A" "pty,raw,echo=0,link=$W/B" \
  2>"$W/socat.err" &
PIDS+=($!)
if ! wait_for_path "$W/A" || ! wait_for_path "$W/B"; then cat "$W/socat.err" >&2; exit 1; fi
taskset -c "$SERVER_CPU" "$BIN/drivegate" sim nidec-washer --plugin-dir "$PLUGINS" \
  --link "$W/line" </dev/null >"$W/sim.log" 2>&1 &
PIDS+=($!)
wait_for_path "$W/line" || { cat "$W/sim.log" >&2; exit 1; }

echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr); daemon, socat and simulator on CPU $SERVER_CPU, master on CPU $LOAD_CPU;" \
  "load average at start: $(cut -d' ' -f1-3 /proc/loadavg); master: ${MASTER[*]}; daemon and socat: ${SERVER[*]}"
probe=$("${MASTER[@]}" "$BIN/dg-serial-listener-bench" --probe "$W/A" "$W/B" --count 1000)
echo "pty pair through socat, write() -> first byte read, us: $probe"
# The framer's 1.5-character rule applied by a reader thread on the daemon's CPU and policy, to
# the transport alone: the frames it would cut with no daemon involved.
for baud in $BAUDS; do
  "${MASTER[@]}" "$BIN/dg-serial-listener-bench" --frames "$W/A" "$W/B" "$SERVER_CPU" \
    --baud "$baud" --count 1000
done
echo
echo "| round | baud | n | ok | no/wrong reply | master late | char us | t3.5 us | req/s | wire limit req/s | ratio | ratio answered | gap p50 / p99 / max us | above t3.5 p50 / p99 us |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"

status=0
COUNTERS=()
for round in $(seq "$ROUNDS"); do
  for baud in $BAUDS; do
    count_var=COUNT_$baud
    count=${!count_var:-$([[ $baud -le 19200 ]] && echo 500 || echo 2000)}
    cat >"$W/dg.toml" <<EOF
[[listener]]
address = "127.0.0.1:$PORT"
access = "operate"
allow = ["127.0.0.1"]

[[listener]]
port = "$W/B"
baud = $baud
framing = "rtu"
access = "operate"
${RX_LATENCY_MS:+rx_latency_ms = $RX_LATENCY_MS}

[[bus]]
name = "line"
port = "$W/line"

[[device]]
name = "washer"
bus = "line"
adapter = "nidec-washer"
unit_id = 1

[http]
listen = "127.0.0.1:$HTTP_PORT"
requests_per_s = 0
EOF
    "${SERVER[@]}" "$BIN/drivegated" -c "$W/dg.toml" -p "$PLUGINS" --log-level info \
      >"$W/dg.log" 2>&1 &
    DG=$!
    PIDS+=("$DG")
    for _ in $(seq 100); do grep -q '(rtu): .* open' "$W/dg.log" 2>/dev/null && break; sleep 0.1; done
    set +e
    line=$("${MASTER[@]}" "$BIN/dg-serial-listener-bench" --port "$W/A" --baud "$baud" \
      --timeout-ms "$TIMEOUT_MS" \
      --count "$count" --qty "$QTY" --addr "$ADDR" --label "r$round" --gaps "$W/gaps-$round-$baud" \
      2>"$W/master-$round-$baud.err")
    rc=$?
    # The listener's own counters (docs/serial-listeners.md), for what went unanswered and why.
    counters=$(python3 - "$HTTP_PORT" <<'PY'
import json, sys, urllib.request
try:
    s = json.load(urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/api/v1/status", timeout=5))
    for l in s.get("serial_listeners", []):
        if l.get("framing") == "rtu" and not str(l.get("port", "")).count(":"):
            print(" ".join(f"{k}={l.get(k)}" for k in ("requests", "not_answered", "broken_frames",
                                                        "crc_errors", "overruns", "frames")))
except Exception as e:
    print(f"status unavailable: {e}")
PY
)
    set -e
    ((rc == 0)) || status=1
    kill -TERM "$DG"; wait "$DG" 2>/dev/null || true
    if [[ -n $KEEP_DIR ]]; then
      mkdir -p "$KEEP_DIR"
      cp "$W/gaps-$round-$baud" "$KEEP_DIR/" 2>/dev/null || true
      cp "$W/dg.log" "$KEEP_DIR/dg-$round-$baud.log"
      cp "$W/master-$round-$baud.err" "$KEEP_DIR/"
    fi
    COUNTERS+=("round $round, $baud baud: listener $counters")
    if [[ -z $line ]]; then
      echo "| $round | $baud | - | master failed (status $rc); daemon log: $(tail -3 "$W/dg.log" | tr '\n' ' ') |"
      continue
    fi
    # key=value -> an associative array
    declare -A v=()
    for kv in $line; do [[ $kv == *=* ]] && v[${kv%%=*}]=${kv#*=}; done
    echo "| $round | $baud | ${v[n]} | ${v[ok]} | ${v[no_reply]} / ${v[wrong]} | ${v[master_late]} |" \
      "${v[char_us]} | ${v[t35_us]} | ${v[rps]} | ${v[limit_rps]} | ${v[ratio]} | ${v[ratio_answered]} |" \
      "${v[gap_p50_us]} / ${v[gap_p99_us]} / ${v[gap_max_us]} | ${v[above_t35_p50_us]} / ${v[above_t35_p99_us]} |"
    unset v
  done
done
echo
printf '%s\n' "${COUNTERS[@]}"
exit $status
