#!/usr/bin/env bash
# bench/serial_tcp.sh [BUILD_DIR]: serial efficiency of a bus behind a serial device server
# (`port = "tcp://..."` through Debian's ser2net) against the same drive on a local pty, same run.
#
# The measurement is bench/serial.sh's, for one polled adapter ($ADAPTER, default ed3100): a
# simulated drive in wire-timing mode (`drivegate sim --wire-timing`), drivegated polling it every
# POLL_MS, and for SECONDS_EACH seconds a setpoint write every WRITE_MS over Modbus TCP
# (bench/cmdlat.py); bench/serial_report.py computes poll cycles, the wire limit, efficiency, the
# gateway's gap and the command latency from the simulator's wire log. Two sides:
#   pty: the bus's port is the simulator's pty link, as in bench/serial.sh;
#   tcp: the bus's port is tcp://127.0.0.1:$S2N_PORT, network_delay_ms = 0 (loopback), served by
#        one ser2net (`accepter: tcp,127.0.0.1,PORT`, `connector: serialdev,LINK,SETTINGS,local`,
#        as tests/support/ser2net.h runs it) in front of an identical simulator on the same link.
# Each run starts a fresh simulator (its own wire log) and a fresh drivegated; ser2net runs for
# the whole script (it opens the pty only while drivegated is connected). For ROUNDS rounds the
# order alternates (pty first in odd rounds, tcp first in even ones). Prints each run's row, the
# medians per side over the rounds and the ratio tcp / pty.
# The wire log is the line's view: on the tcp side, the gap between a reply's last byte and the
# next request's first byte includes the trip through ser2net both ways, ser2net's own wait
# before it forwards what it read from the device (chardelay: 2 characters, at least 1 ms, by
# default) and drivegated's required inter-frame silence, which it times from when the reply
# reached it.
# Environment: ADAPTER (ed3100 | unicla-edrive | mdriver-2400 | nidec-washer), ROUNDS (4),
#   SECONDS_EACH (8), POLL_MS (200), WRITE_MS (150), TURNAROUND_US (2000), PORT (15080: Modbus),
#   S2N_PORT (15081), NODELAY (0; 1: `accepter: tcp(nodelay),...`, ser2net sets TCP_NODELAY),
#   CHARDELAY ("": ser2net's default; "false": `chardelay: false`), KEEP_DIR
#   (a directory: each run's wire log, write log, configuration and daemon log are copied there).
set -euo pipefail
B=$(realpath "${1:-build-bench}")
BIN=$B/bin
PLUGINS=$B/adapters
HERE=$(dirname "$(realpath "$0")")
ADAPTER=${ADAPTER:-ed3100}
ROUNDS=${ROUNDS:-4}
SECONDS_EACH=${SECONDS_EACH:-8}
POLL_MS=${POLL_MS:-200}
WRITE_MS=${WRITE_MS:-150}
TURNAROUND_US=${TURNAROUND_US:-2000}
PORT=${PORT:-15080}
S2N_PORT=${S2N_PORT:-15081}
CHARDELAY=${CHARDELAY:-}
KEEP_DIR=${KEEP_DIR:-}
NODELAY=${NODELAY:-0}
SER2NET=/usr/sbin/ser2net

for f in "$BIN/drivegated" "$BIN/drivegate" "$SER2NET"; do
  [[ -x $f ]] || { echo "serial_tcp.sh: $f missing" >&2; exit 2; }
done
((ROUNDS % 2 == 0)) || echo "serial_tcp.sh: ROUNDS=$ROUNDS is odd: pty goes first once more" >&2

# Per adapter (as bench/serial.sh): the line ser2net opens the pty with (the adapter's default; a
# pty keeps only the speed, see tests/support/ser2net.h, but ser2net's chardelay is computed from
# it) and the adapter's inter-frame silence (its driver's traits()).
opt=()
dev_opt=""
case $ADAPTER in
  ed3100) settings=9600e81; gap_ms=10 ;;
  mdriver-2400) settings=2400n81; gap_ms=10 ;;
  unicla-edrive) settings=19200n81; gap_ms=5 ;;
  nidec-washer) settings=2400e81; gap_ms=0; dev_opt="platform = 7"; opt=(--set platform=7) ;;
  *) echo "serial_tcp.sh: ADAPTER must be a polled adapter (not $ADAPTER)" >&2; exit 2 ;;
esac
SETTINGS=${SETTINGS:-$settings}

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir sertcp

LINK=$W/dev
{
  echo "connection: &bench"
  echo "  accepter: tcp$( ((NODELAY)) && echo '(nodelay)'),127.0.0.1,$S2N_PORT"
  echo "  connector: serialdev,$LINK,$SETTINGS,local"
  echo "  options:"
  echo "    kickolduser: true"
  [[ -n $CHARDELAY ]] && echo "    chardelay: $CHARDELAY"
} >"$W/ser2net.yaml"
"$SER2NET" -n -d -u -c "$W/ser2net.yaml" >"$W/ser2net.log" 2>&1 &
PIDS+=($!)
wait_for_port "$S2N_PORT" || { cat "$W/ser2net.log" >&2; exit 1; }

run() {  # run SIDE ROUND
  local side=$1 round=$2 tag=$1-$2 port sim dg
  "$BIN/drivegate" sim "$ADAPTER" --plugin-dir "$PLUGINS" --link "$LINK" "${opt[@]}" --wire-timing \
    --turnaround-us "$TURNAROUND_US" --wire-log "$W/$tag.wire" </dev/null >"$W/$tag.sim" 2>&1 &
  sim=$!
  PIDS+=("$sim")
  wait_for_path "$LINK" || true
  port=$LINK
  [[ $side == tcp ]] && port=tcp://127.0.0.1:$S2N_PORT
  {
    echo "[server]"; echo "listen = \"127.0.0.1:$PORT\""
    echo "[[bus]]"; echo "name = \"b\""; echo "port = \"$port\""
    [[ $side == tcp ]] && echo "network_delay_ms = 0"
    echo "[[device]]"; echo "name = \"$ADAPTER\""; echo "bus = \"b\""; echo "adapter = \"$ADAPTER\""
    echo "unit_id = 1"; echo "poll_ms = $POLL_MS"
    [[ -n $dev_opt ]] && { echo "[device.options]"; echo "$dev_opt"; }
  } >"$W/$tag.toml"
  "$BIN/drivegated" --config "$W/$tag.toml" --plugin-dir "$PLUGINS" --log-level warn \
    >"$W/$tag.log" 2>&1 &
  dg=$!
  PIDS+=("$dg")
  wait_for_port "$PORT" || { cat "$W/$tag.log" >&2; exit 1; }
  python3 "$HERE/cmdlat.py" "$PORT" "$SECONDS_EACH" "$WRITE_MS" "$W/$tag.writes"
  kill "$dg"; wait "$dg" 2>/dev/null || true
  kill "$sim"; wait "$sim" 2>/dev/null || true
  rm -f "$LINK"
  if [[ -n $KEEP_DIR ]]; then cp "$W/$tag".* "$KEEP_DIR/"; fi
  PIDS=("${PIDS[0]}")  # ser2net only
  local sim_line row
  sim_line=$(head -2 "$W/$tag.sim" | tail -1)
  row=$(python3 "$HERE/serial_report.py" "$ADAPTER" "$W/$tag.wire" "$W/$tag.writes" \
    "$TURNAROUND_US" "$sim_line" "$gap_ms" 0)
  row=${row%%$'\n'*}
  echo "$side $round $row" >>"$W/results.txt"
  echo "| $side | $round $row"
  grep -i "error\|critical" "$W/$tag.log" | head -3 >&2 || true
}

echo "| side | round | adapter | char us | frame gap ms | tx/cycle | cycles | cycle ms | limit ms | eff | limit+gap ms | eff+gap | gateway gap us p50 / p99 | above silence us p50 / p99 | command latency ms p50 / p99 |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for round in $(seq "$ROUNDS"); do
  if ((round % 2 == 1)); then
    run pty "$round"; run tcp "$round"
  else
    run tcp "$round"; run pty "$round"
  fi
done

echo
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr), $("$SER2NET" -v 2>&1 | head -1); adapter $ADAPTER, ser2net $SETTINGS" \
  "chardelay ${CHARDELAY:-default}, nodelay $NODELAY, turnaround ${TURNAROUND_US} us, poll_ms $POLL_MS, a write" \
  "every $WRITE_MS ms; $ROUNDS rounds x ${SECONDS_EACH}s per side; network_delay_ms = 0"
python3 "$HERE/serial_tcp_summary.py" "$W/results.txt"
