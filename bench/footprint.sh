#!/usr/bin/env bash
# bench/footprint.sh [BUILD_DIR]: the daemon's RSS and idle CPU, with no Modbus TCP load.
#   five: the five demo drives, one per bus, each on its own `drivegate sim`
#   32x4: 32 buses of 4 simulated ed3100 drives each (addresses 1..4 on one sim per bus)
# CPU is utime+stime of drivegated from /proc/<pid>/stat over SECONDS_EACH seconds, after a
# settling time; device polls are the increase of frames_good (input registers 9..10) summed over
# every unit in the same window, so CPU per device-poll = CPU time / good frames.
set -euo pipefail
B=$(realpath "${1:-build-bench}")
BIN=$B/bin
PLUGINS=$B/adapters
HERE=$(dirname "$(realpath "$0")")
SECONDS_EACH=${SECONDS_EACH:-20}
PORT=${PORT:-15050}
# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir foot

ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }

measure() {  # measure NAME CONFIG UNITS...
  local name=$1 config=$2; shift 2
  "$BIN/drivegated" --config "$config" --plugin-dir "$PLUGINS" --log-level warn \
    >"$W/$name.log" 2>&1 &
  local dg=$!
  PIDS+=("$dg")
  wait_for_port "$PORT"
  sleep 3
  local f0 f1 t0 t1 hz rss
  hz=$(getconf CLK_TCK)
  f0=$(python3 "$HERE/mbwrite.py" --frames "$PORT" "$@")
  t0=$(ticks $dg)
  sleep "$SECONDS_EACH"
  t1=$(ticks $dg)
  f1=$(python3 "$HERE/mbwrite.py" --frames "$PORT" "$@")
  rss=$(awk '/VmRSS/ {print $2}' "/proc/$dg/status")
  python3 - "$name" "$#" "$rss" "$t0" "$t1" "$hz" "$f0" "$f1" "$SECONDS_EACH" <<'PY'
import sys
name, units, rss, t0, t1, hz, f0, f1, secs = sys.argv[1:]
cpu_s = (int(t1) - int(t0)) / int(hz)
polls = int(f1) - int(f0)
per = cpu_s * 1e6 / polls if polls else float("nan")
print(f"| {name} | {units} | {int(rss) / 1024:.1f} | {100 * cpu_s / float(secs):.2f} | "
      f"{polls / float(secs):.0f} | {per:.1f} |")
PY
  kill $dg; wait $dg 2>/dev/null || true
}

echo "| setup | devices | RSS MiB | CPU % (of one core) | device polls/s | CPU us per device-poll |"
echo "|---|---|---|---|---|---|"
# five demo drives
cfg=$W/five.toml
{ echo "[server]"; echo "listen = \"127.0.0.1:$PORT\""; } >"$cfg"
unit=0
for d in "nidec-washer platform=7" "ed3100 -" "mdriver-2400 -" "fdc1 slave_mode=true" "unicla-edrive -"; do
  read -r id opt <<<"$d"
  unit=$((unit + 1))
  set_arg=()
  [[ $opt != - ]] && set_arg=(--set "$opt")
  "$BIN/drivegate" sim "$id" --plugin-dir "$PLUGINS" --link "$W/$id" "${set_arg[@]}" \
    </dev/null >/dev/null 2>&1 &
  PIDS+=($!)
  wait_for_path "$W/$id" || true
  { echo "[[bus]]"; echo "name = \"$id\""; echo "port = \"$W/$id\""
    echo "[[device]]"; echo "name = \"$id\""; echo "bus = \"$id\""; echo "adapter = \"$id\""
    echo "unit_id = $unit"
    if [[ $opt != - ]]; then echo "[device.options]"; echo "${opt%%=*} = ${opt#*=}"; fi
  } >>"$cfg"
done
measure five "$cfg" 1 2 3 4 5

# 32 buses x 4 ed3100 drives
cfg=$W/many.toml
{ echo "[server]"; echo "listen = \"127.0.0.1:$PORT\""; } >"$cfg"
units=()
for b in $(seq 32); do
  "$BIN/drivegate" sim ed3100 --plugin-dir "$PLUGINS" --link "$W/bus$b" --address 1 --address 2 \
    --address 3 --address 4 </dev/null >/dev/null 2>&1 &
  PIDS+=($!)
  wait_for_path "$W/bus$b" || true
  { echo "[[bus]]"; echo "name = \"bus$b\""; echo "port = \"$W/bus$b\""; } >>"$cfg"
  for a in 1 2 3 4; do
    u=$(((b - 1) * 4 + a))
    units+=("$u")
    { echo "[[device]]"; echo "name = \"d$u\""; echo "bus = \"bus$b\""; echo "adapter = \"ed3100\""
      echo "unit_id = $u"; echo "address = $a"; } >>"$cfg"
  done
done
measure 32x4 "$cfg" "${units[@]}"
