#!/usr/bin/env bash
# bench/serial.sh [BUILD_DIR]: serial efficiency and command latency.
#
# For each adapter: one simulated drive in wire-timing mode (each byte takes its character time at
# the adapter's default baud and framing, replies start TURNAROUND_US after the request's last
# character), drivegated polling it every POLL_MS, and for SECONDS seconds a setpoint write every
# WRITE_MS over Modbus TCP. The simulator's wire log gives the poll cycles, the wire limit, the
# gateway's own gap, and the time from each write to the first native byte it caused.
set -euo pipefail
B=$(realpath "${1:-build-bench}")
BIN=$B/bin
PLUGINS=$B/adapters
HERE=$(dirname "$(realpath "$0")")
TURNAROUND_US=${TURNAROUND_US:-2000}
POLL_MS=${POLL_MS:-200}
SECONDS_EACH=${SECONDS_EACH:-8}
WRITE_MS=${WRITE_MS:-150}
PORT=${PORT:-15040}
ADAPTERS=${ADAPTERS:-"nidec-washer ed3100 mdriver-2400 fdc1 unicla-edrive"}

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir serial

echo "| adapter | char us | frame gap ms | tx/cycle | cycles | cycle ms | limit ms | eff | limit+gap ms | eff+gap | gateway gap us p50 / p99 | above silence us p50 / p99 | command latency ms p50 / p99 |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for id in $ADAPTERS; do
  opt=()
  dev_opt=""
  gap_ms=0  # the adapter's traits().inter_frame_gap (its driver.cpp)
  streaming=0
  case $id in
    nidec-washer) dev_opt="platform = 7"; opt=(--set platform=7) ;;
    fdc1) dev_opt="slave_mode = true"; opt=(--set slave_mode=true); streaming=1 ;;
    ed3100) gap_ms=10 ;;
    mdriver-2400) gap_ms=10 ;;
    unicla-edrive) gap_ms=5 ;;
  esac
  "$BIN/drivegate" sim "$id" --plugin-dir "$PLUGINS" --link "$W/$id" "${opt[@]}" --wire-timing \
    --turnaround-us "$TURNAROUND_US" --wire-log "$W/$id.wire" </dev/null >"$W/$id.sim" 2>&1 &
  SIM=$!
  wait_for_path "$W/$id" || true
  {
    echo "[server]"; echo "listen = \"127.0.0.1:$PORT\""
    echo "[[bus]]"; echo "name = \"b\""; echo "port = \"$W/$id\""
    echo "[[device]]"; echo "name = \"$id\""; echo "bus = \"b\""; echo "adapter = \"$id\""
    echo "unit_id = 1"; echo "poll_ms = $POLL_MS"
    [[ -n $dev_opt ]] && { echo "[device.options]"; echo "$dev_opt"; }
  } >"$W/$id.toml"
  "$BIN/drivegated" --config "$W/$id.toml" --plugin-dir "$PLUGINS" --log-level warn \
    >"$W/$id.log" 2>&1 &
  DG=$!
  PIDS=("$SIM" "$DG")
  wait_for_port "$PORT"
  python3 "$HERE/cmdlat.py" "$PORT" "$SECONDS_EACH" "$WRITE_MS" "$W/$id.writes"
  kill $DG $SIM; wait $DG $SIM 2>/dev/null || true
  PIDS=()
  sim_line=$(head -2 "$W/$id.sim" | tail -1)
  python3 "$HERE/serial_report.py" "$id" "$W/$id.wire" "$W/$id.writes" "$TURNAROUND_US" "$sim_line" "$gap_ms" "$streaming"
done
