#!/usr/bin/env bash
# bench/mqtt.sh [BUILD_DIR]: the MQTT Sparkplug B northbound, on a real broker.
#
# A mosquitto (/usr/sbin/mosquitto) on 127.0.0.1:$MQTT_PORT with its configuration in the work
# directory, anonymous, no persistence. Two parts (PARTS, default both):
#
#   latency  from the native frame that changes a value to the DDATA at a subscriber. One
#            simulated nidec-washer (poll_ms $LAT_POLL_MS), a drivegated with [mqtt]
#            (min_interval_ms = 0, default deadband: any change) and [http] capture = true; the
#            drive is started over Modbus (command 1, $LAT_RPM rpm) with accel_time_ms
#            $LAT_ACCEL_MS, so its speed climbs slowly and every poll reads a new speed. For
#            $LAT_SECONDS: `drivegate capture` of the bus (each frame stamped, CLOCK_REALTIME us,
#            when drivegated finished reading it) and `mosquitto_sub -F '%U %t %x'` (receive
#            time, CLOCK_REALTIME ns). Each DDATA is paired with the received frame that carried
#            its speed_rpm value (bench/mqtt_report.py); p50/p90/p99/max of the difference.
#   load     $BUSES buses x $PER_BUS simulated ed3100 drives (one `drivegate sim ed3100
#            --address 1..N` per bus, as bench/footprint.sh), poll_ms $POLL_MS. Every $STIM_MS
#            bench/mqtt_stimulus.py sets a new output current on every simulated drive (an
#            operator command on the simulator's stdin: the daemon sees only its own polls), so
#            every device always has something to publish. One subscriber (mosquitto_sub on
#            spBv1.0/#) runs throughout, as a SCADA host would. Then ROUNDS x (a drivegated
#            with [mqtt], then the same configuration without [mqtt]): ABAB, each a fresh
#            daemon, WARMUP s, then DURATION s measured: utime+stime of drivegated and of
#            mosquitto from /proc/<pid>/stat (CPU seconds per wall second), VmRSS and VmHWM of
#            drivegated from /proc/<pid>/status at the end, messages the subscriber received in
#            the window, good frames (frames_good summed over every unit, as footprint.sh), and the
#            CPU the rest of the machine used meanwhile (busy time from /proc/stat minus every
#            process this script started). With LAT_UNDER_LOAD=1 (default), the latency part
#            once more afterwards, its daemon beside a running 32x4 daemon with [mqtt].
#
# Before each measured run the 1-minute load average is checked: above $LOAD_MAX, wait
# (60 s at a time, $LOAD_WAIT s at most, then measure anyway and say so). The load before each
# run is printed with its figures. Nothing is pinned: both parts measure the whole path (daemon,
# broker, subscriber) as it runs on the machine.
#
# Environment: PARTS ("latency load"), LAT_SECONDS (60), LAT_POLL_MS (100), LAT_RPM (1500),
#   LAT_ACCEL_MS (100000: 15 rpm/s, 1.5 rpm per poll), ROUNDS (2), DURATION (30 s), WARMUP (10 s),
#   BUSES (32), PER_BUS (4), POLL_MS (100), STIM_MS (100), LOAD_MAX (1.5), LOAD_WAIT (600 s),
#   MQTT_PORT (15271), DG_PORT (15270), HTTP_PORT (15272), LAT_DG_PORT (15273),
#   LAT_UNDER_LOAD (1), MOSQUITTO (/usr/sbin/mosquitto).
set -euo pipefail

B=$(realpath "${1:-build-bench}")
BIN=$B/bin
PLUGINS=$B/adapters
HERE=$(dirname "$(realpath "$0")")
PARTS=${PARTS:-"latency load"}
LAT_SECONDS=${LAT_SECONDS:-60}
LAT_POLL_MS=${LAT_POLL_MS:-100}
LAT_RPM=${LAT_RPM:-1500}
LAT_ACCEL_MS=${LAT_ACCEL_MS:-100000}
ROUNDS=${ROUNDS:-2}
DURATION=${DURATION:-30}
WARMUP=${WARMUP:-10}
BUSES=${BUSES:-32}
PER_BUS=${PER_BUS:-4}
POLL_MS=${POLL_MS:-100}
STIM_MS=${STIM_MS:-100}
LOAD_MAX=${LOAD_MAX:-1.5}
LOAD_WAIT=${LOAD_WAIT:-600}
MQTT_PORT=${MQTT_PORT:-15271}
DG_PORT=${DG_PORT:-15270}
HTTP_PORT=${HTTP_PORT:-15272}
LAT_DG_PORT=${LAT_DG_PORT:-15273}
LAT_UNDER_LOAD=${LAT_UNDER_LOAD:-1}
MOSQUITTO=${MOSQUITTO:-/usr/sbin/mosquitto}

for f in "$BIN/drivegated" "$BIN/drivegate" "$MOSQUITTO" "$(command -v mosquitto_sub || true)"; do
  [[ -n $f && -x $f ]] || { echo "mqtt.sh: ${f:-mosquitto_sub} missing" >&2; exit 2; }
done

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir mqtt

HZ=$(getconf CLK_TCK)
ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
ticks_of_all() {  # the CPU ticks of every process this script started that still runs
  local p sum=0 t
  for p in "${PIDS[@]}"; do
    t=$(awk '{print $14 + $15}' "/proc/$p/stat" 2>/dev/null) || continue
    sum=$((sum + t))
  done
  echo "$sum"
}
busy_ticks() { awk '/^cpu / {print $2 + $3 + $4 + $7 + $8 + $9}' /proc/stat; }
status_kb() { awk -v k="$2:" '$1 == k {print $2}' "/proc/$1/status"; }

start_daemon() {  # start_daemon CONFIG LOG [PORT]: sets DG_PID
  "$BIN/drivegated" --config "$1" --plugin-dir "$PLUGINS" --log-level info >"$2" 2>&1 &
  DG_PID=$!
  PIDS+=("$DG_PID")
  if ! wait_for_port "${3:-$DG_PORT}" || ! sleep 0.2 || ! kill -0 "$DG_PID" 2>/dev/null; then
    echo "mqtt.sh: drivegated did not start (port ${3:-$DG_PORT} in use?)" >&2
    cat "$2" >&2
    exit 1
  fi
}
stop_daemon() {
  kill "$DG_PID" 2>/dev/null || true
  wait "$DG_PID" 2>/dev/null || true
}

# ---- the broker ---------------------------------------------------------------------------------
cat >"$W/mosquitto.conf" <<EOF
listener $MQTT_PORT 127.0.0.1
allow_anonymous true
persistence false
log_dest file $W/mosquitto.log
log_type error
log_type warning
EOF
"$MOSQUITTO" -c "$W/mosquitto.conf" >"$W/mosquitto.out" 2>&1 &
MOSQ_PID=$!
PIDS+=("$MOSQ_PID")
if ! wait_for_port "$MQTT_PORT" || ! sleep 0.2 || ! kill -0 "$MOSQ_PID" 2>/dev/null; then
  echo "mqtt.sh: mosquitto did not start (port $MQTT_PORT in use?)" >&2
  cat "$W/mosquitto.out" "$W/mosquitto.log" >&2
  exit 1
fi

mqtt_toml() {  # mqtt_toml EDGE_NODE [MIN_INTERVAL_MS]
  printf '[mqtt]\nbroker = "mqtt://127.0.0.1:%s"\ngroup_id = "bench"\nedge_node_id = "%s"\n' \
    "$MQTT_PORT" "$1"
  [[ -n ${2:-} ]] && printf 'min_interval_ms = %s\n' "$2"
  return 0
}

echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr), $("$MOSQUITTO" -h 2>&1 | head -1); build $B" \
  "($(awk -F= '/^CMAKE_BUILD_TYPE/ {print $2}' "$B/CMakeCache.txt" 2>/dev/null))"

# ---- latency --------------------------------------------------------------------------------------
latency_part() {  # latency_part TAG MODBUS_PORT WHAT
  local d=$W/$1 port=$2
  mkdir -p "$d"
  "$BIN/drivegate" sim nidec-washer --plugin-dir "$PLUGINS" --link "$d/washer" --set platform=7 \
    </dev/null >"$d/sim.out" 2>&1 &
  local sim=$!
  PIDS+=("$sim")
  wait_for_path "$d/washer"
  {
    printf '[server]\nlisten = "127.0.0.1:%s"\n\n' "$port"
    printf '[http]\nlisten = "127.0.0.1:%s"\ncapture = true\n\n' "$HTTP_PORT"
    mqtt_toml lat 0
    printf '\n[[bus]]\nname = "washer"\nport = "%s"\n' "$d/washer"
    printf '\n[[device]]\nname = "washer"\nbus = "washer"\nadapter = "nidec-washer"\n'
    printf 'unit_id = 1\npoll_ms = %s\n[device.options]\nplatform = 7\naccel_time_ms = %s\n' \
      "$LAT_POLL_MS" "$LAT_ACCEL_MS"
  } >"$d/lat.toml"
  # The subscriber first, so it sees the births (DDATA metrics come by alias).
  stdbuf -oL mosquitto_sub -p "$MQTT_PORT" -t 'spBv1.0/bench/+/lat/#' -F '%U %t %x' \
    >"$d/sub.txt" 2>"$d/sub.err" &
  local sub=$!
  PIDS+=("$sub")
  sleep 0.5
  [[ $1 == lat ]] && wait_load
  local load_before
  load_before=$(cut -d' ' -f1 /proc/loadavg)
  start_daemon "$d/lat.toml" "$d/drivegated.log" "$port"
  python3 "$HERE/mbwrite.py" --wait-online "$port" "1:0=1,$LAT_RPM"
  sleep 2
  "$BIN/drivegate" capture --bus washer --seconds "$LAT_SECONDS" -w "$d/bus.pcap" \
    --http "127.0.0.1:$HTTP_PORT"
  sleep 0.5
  local load_after
  load_after=$(cut -d' ' -f1 /proc/loadavg)
  stop_daemon
  kill "$sub" "$sim" 2>/dev/null || true
  echo
  echo "## latency$3: native frame -> DDATA at the subscriber (nidec-washer, poll" \
    "${LAT_POLL_MS} ms, min_interval_ms 0, ${LAT_SECONDS} s; load $load_before before," \
    "$load_after after)"
  python3 "$HERE/mqtt_report.py" latency "$d/bus.pcap" "$d/sub.txt" washer speed_rpm
  grep -E " (warning|error|critical) " "$d/drivegated.log" | grep -v "lets every address" |
    head -5 || true
}

# ---- load -----------------------------------------------------------------------------------------
load_part() {
  local d=$W/load b a u fd fifos=() units=() addrs
  mkdir -p "$d"
  addrs=$(seq -s, "$PER_BUS")
  {
    printf '[server]\nlisten = "127.0.0.1:%s"\nmax_clients = 8\n' "$DG_PORT"
  } >"$d/base.toml"
  for b in $(seq "$BUSES"); do
    mkfifo "$d/bus$b.in"
    # shellcheck disable=SC2034 # fd: held open so the simulator never reads an end of file
    exec {fd}<>"$d/bus$b.in"
    fifos+=("$d/bus$b.in")
    local args=()
    for a in $(seq "$PER_BUS"); do args+=(--address "$a"); done
    "$BIN/drivegate" sim ed3100 --plugin-dir "$PLUGINS" --link "$d/bus$b" "${args[@]}" \
      <"$d/bus$b.in" >/dev/null 2>&1 &
    PIDS+=($!)
    printf '\n[[bus]]\nname = "bus%s"\nport = "%s"\n' "$b" "$d/bus$b" >>"$d/base.toml"
    for a in $(seq "$PER_BUS"); do
      u=$(((b - 1) * PER_BUS + a))
      units+=("$u")
      printf '\n[[device]]\nname = "d%s"\nbus = "bus%s"\nadapter = "ed3100"\nunit_id = %s\n' \
        "$u" "$b" "$u" >>"$d/base.toml"
      printf 'address = %s\npoll_ms = %s\n' "$a" "$POLL_MS" >>"$d/base.toml"
    done
  done
  for b in $(seq "$BUSES"); do wait_for_path "$d/bus$b"; done
  cp "$d/base.toml" "$d/no-mqtt.toml"
  { mqtt_toml load; cat "$d/base.toml"; } >"$d/mqtt.toml"
  # mqtt_toml goes first: [mqtt] must not land inside the last [[device]]; [server] then follows
  # it as its own table.
  python3 "$HERE/mqtt_stimulus.py" "$STIM_MS" "$addrs" "${fifos[@]}" &
  PIDS+=($!)
  stdbuf -oL mosquitto_sub -p "$MQTT_PORT" -t 'spBv1.0/#' -F '%U %t' >"$d/sub.txt" 2>"$d/sub.err" &
  PIDS+=($!)

  : >"$d/results.txt"
  local round side
  for round in $(seq "$ROUNDS"); do
    for side in mqtt no-mqtt; do
      wait_load
      local load_before=$LOAD
      start_daemon "$d/$side.toml" "$d/$side-$round.log"
      sleep "$WARMUP"
      local f0 f1 t0 t1 m0 m1 a0 a1 c0 c1 w0 w1 rss hwm
      f0=$(python3 "$HERE/mbwrite.py" --frames "$DG_PORT" "${units[@]}")
      w0=$(date +%s.%N)
      t0=$(ticks "$DG_PID"); m0=$(ticks "$MOSQ_PID"); a0=$(ticks_of_all); c0=$(busy_ticks)
      sleep "$DURATION"
      t1=$(ticks "$DG_PID"); m1=$(ticks "$MOSQ_PID"); a1=$(ticks_of_all); c1=$(busy_ticks)
      w1=$(date +%s.%N)
      f1=$(python3 "$HERE/mbwrite.py" --frames "$DG_PORT" "${units[@]}")
      rss=$(status_kb "$DG_PID" VmRSS)
      hwm=$(status_kb "$DG_PID" VmHWM)
      stop_daemon
      local msgs
      msgs=$(awk -v a="$w0" -v b="$w1" '$1 >= a && $1 < b' "$d/sub.txt" | wc -l)
      awk -v run="$round" -v side="$side" -v load="$load_before" -v hz="$HZ" \
        -v t0="$t0" -v t1="$t1" -v m0="$m0" -v m1="$m1" -v a0="$a0" -v a1="$a1" -v c0="$c0" \
        -v c1="$c1" -v w0="$w0" -v w1="$w1" -v f0="$f0" -v f1="$f1" -v rss="$rss" -v hwm="$hwm" \
        -v msgs="$msgs" 'BEGIN {
          s = w1 - w0
          printf "run=%s side=%s load=%s secs=%.2f dg_cpu=%.4f mosq_cpu=%.4f rss_kb=%s hwm_kb=%s " \
                 "msgs=%.1f polls=%.1f other_cpu=%.3f ours_cpu=%.3f\n", run, side, load, s,
                 (t1 - t0) / hz / s, (m1 - m0) / hz / s, rss, hwm, msgs / s, (f1 - f0) / s,
                 ((c1 - c0) - (a1 - a0)) / hz / s, (a1 - a0) / hz / s
        }' | tee -a "$d/results.txt" >&2
      grep -E " (warning|error|critical) " "$d/$side-$round.log" | grep -v "lets every address" |
        head -3 >&2 || true
    done
  done
  echo
  echo "## load: $BUSES buses x $PER_BUS ed3100, poll ${POLL_MS} ms, stimulus every ${STIM_MS} ms;" \
    "$ROUNDS x (with [mqtt], without), ${WARMUP} s warm-up, ${DURATION} s measured"
  python3 "$HERE/mqtt_report.py" load "$d/results.txt"
  if ((LAT_UNDER_LOAD)); then
    # The latency again, beside the 32x4 edge node publishing through the same broker.
    start_daemon "$d/mqtt.toml" "$d/busy.log"
    local busy_pid=$DG_PID
    sleep "$WARMUP"
    latency_part latbusy "$LAT_DG_PORT" " beside the ${BUSES}x${PER_BUS} edge node"
    DG_PID=$busy_pid
    stop_daemon
  fi
}

for part in $PARTS; do
  case $part in
    latency) latency_part lat "$LAT_DG_PORT" "" ;;
    load) load_part ;;
    *) echo "mqtt.sh: unknown part $part" >&2; exit 2 ;;
  esac
done
