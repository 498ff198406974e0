#!/usr/bin/env bash
# bench/replay_cost.sh [BUILD_DIR] [OLD_BIN_DIR]: what a store-and-forward replay at the highest
# rate the configuration accepts (replay_per_s = 100000) costs a PLC's Modbus latency, against the
# same daemon with nothing to replay, side by side in one run. With OLD_BIN_DIR (another build's
# bin/, e.g. main's), its drivegated is measured the same way beside this one.
#
# Each daemon (pinned to CPU $SERVER_CPU) polls five simulated drives (bench/lib.sh) and has
# [mqtt] on a local mosquitto (pinned to $LOAD_CPU, no subscriber) with a state directory. For
# ROUNDS rounds, for each daemon, two phases of DURATION s, each measured by dg-loadgen with one
# connection on its plaintext listener (FC03 16..140 alternating with FC04 0..18, unit 2):
#   quiet   the session online, nothing kept
#   replay  the daemon stopped, RECORDS changes written into its store (bench/store_fill.cpp: the
#           backlog an outage leaves), the daemon started again: measured from its births on,
#           while it replays them as fast as replay_per_s lets it
# The load generator and the simulators run on $LOAD_CPU. Prints each phase's medians and the
# replay p99 over the quiet p99 (the goal: at most 2x), and how many records each replay window
# sent (a window that replayed nothing measures nothing).
# Environment: ROUNDS (3), DURATION (3 s), RECORDS (300000), SERVER_CPU (0), LOAD_CPU (1).
set -euo pipefail

B=$(realpath "${1:-build-bench}")
BIN=$B/bin
OLD=${2:-}
ROUNDS=${ROUNDS:-3}
DURATION=${DURATION:-3}
RECORDS=${RECORDS:-300000}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
HERE=$(dirname "$(realpath "$0")")
for f in drivegated drivegate dg-loadgen dg-store-fill; do
  [[ -e $BIN/$f ]] || { echo "replay_cost.sh: $BIN/$f missing (build with -DDRIVEGATE_BENCH=ON)" >&2; exit 2; }
done

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
# shellcheck source=bench/lib.sh
source "$HERE/lib.sh"
bench_workdir replay

MQTT_PORT=15390
cat >"$W/mosquitto.conf" <<EOF
listener $MQTT_PORT 127.0.0.1
allow_anonymous true
persistence false
max_queued_messages 0
EOF
[[ $(id -u) == 0 ]] && echo "user root" >>"$W/mosquitto.conf"
taskset -c "$LOAD_CPU" /usr/sbin/mosquitto -c "$W/mosquitto.conf" >"$W/mosquitto.log" 2>&1 &
PIDS+=($!)
wait_for_port "$MQTT_PORT"

declare -A PLAIN HTTP PID BINS
TAGS=(new)
BINS[new]=$BIN
if [[ -n $OLD ]]; then TAGS+=(old); BINS[old]=$(realpath "$OLD"); fi
port=15400
for tag in "${TAGS[@]}"; do
  PLAIN[$tag]=$port HTTP[$tag]=$((port + 1))
  port=$((port + 10))
  mkdir -p "$W/$tag/state"
  STATE_DIRECTORY=$W/$tag/state start_gateway "${BINS[$tag]}" "$tag" "[[listener]]
address = \"127.0.0.1:${PLAIN[$tag]}\"
access = \"maintain\"

[http]
listen = \"127.0.0.1:${HTTP[$tag]}\"

[mqtt]
broker = \"mqtt://127.0.0.1:$MQTT_PORT\"
group_id = \"bench\"
edge_node_id = \"$tag\"
replay_per_s = 100000
store_max_mb = 1024"
  PID[$tag]=$GATEWAY_PID
done
for tag in "${TAGS[@]}"; do
  wait_for_port "${PLAIN[$tag]}" || { cat "$W/$tag/drivegated.log" >&2; exit 1; }
  python3 "$HERE/mbwrite.py" --wait-online "${PLAIN[$tag]}" "${START[@]}"
done
sleep 2

store_records() {  # store_records TAG: drivegate_mqtt_store_records of that daemon
  curl -s "http://127.0.0.1:${HTTP[$1]}/metrics" |
    awk '$1 == "drivegate_mqtt_store_records" {print $2}'
}

measure() {  # measure TAG PHASE ROUND: the client's line, into results.txt
  local out before after
  before=$(store_records "$1")
  out=$(taskset -c "$LOAD_CPU" "$BIN/dg-loadgen" --port "${PLAIN[$1]}" --pid "${PID[$1]}" \
    --duration "$DURATION" --warmup 0.3 --unit 2 --small 4:0:19 --large 3:16:125 \
    --connections 1 2>>"$W/loadgen.err") || {
    echo "replay_cost.sh: dg-loadgen failed ($1 $2)" >&2; tail -5 "$W/loadgen.err" >&2
    tail -5 "$W/$1/drivegated.log" >&2; exit 1; }
  after=$(store_records "$1")
  echo "$1 $2 $3 $out replayed=$((${before:-0} - ${after:-0}))" | tee -a "$W/results.txt" >&2
}

# The daemon stopped, its store filled with RECORDS changes, the daemon started again on the same
# configuration (the simulators go on): it replays them once it is born.
refill() {  # refill TAG
  local tag=$1 dir=$W/$1
  kill -TERM "${PID[$tag]}"
  wait "${PID[$tag]}" 2>/dev/null || true
  "$BIN/dg-store-fill" "$dir/state" bench "$tag" nidec-washer "$RECORDS" >/dev/null
  STATE_DIRECTORY=$dir/state taskset -c "$SERVER_CPU" "${BINS[$tag]}/drivegated" \
    --config "$dir/bench.toml" --plugin-dir "${BINS[$tag]}/../adapters" --log-level warn \
    >>"$dir/drivegated.log" 2>&1 &
  PID[$tag]=$!
  PIDS+=("${PID[$tag]}")
  wait_for_port "${PLAIN[$tag]}"
  python3 "$HERE/mbwrite.py" --wait-online "${PLAIN[$tag]}" "${START[@]}"
  for _ in $(seq 50); do  # born: the replay under way
    [[ $(store_records "$tag") -lt $RECORDS ]] && return 0
    sleep 0.1
  done
}

for round in $(seq "$ROUNDS"); do
  for tag in "${TAGS[@]}"; do
    measure "$tag" quiet "$round"
    refill "$tag"
    measure "$tag" replay "$round"
    for _ in $(seq 600); do  # the rest of the backlog gone before the next quiet phase
      [[ $(store_records "$tag") == 0 ]] && break
      sleep 0.1
    done
  done
done

python3 - "$W/results.txt" <<'EOF'
import statistics, sys
rows = {}
for line in open(sys.argv[1]):
    tag, phase, _, *kv = line.split()
    d = dict(x.split("=", 1) for x in kv)
    rows.setdefault((tag, phase), []).append(d)
print("| daemon | phase | Modbus p50 | p99 | p99 / quiet p99 | requests/s | records replayed in the window |")
print("|---|---|---|---|---|---|---|")
for tag in sorted({t for t, _ in rows}):
    quiet = statistics.median(float(r["p99_us"]) for r in rows[(tag, "quiet")])
    for phase in ("quiet", "replay"):
        rs = rows[(tag, phase)]
        med = lambda k: statistics.median(float(r[k]) for r in rs)
        print(f"| {tag} | {phase} | {med('p50_us')/1000:.3f} ms | {med('p99_us')/1000:.3f} ms | "
              f"**{med('p99_us')/quiet:.2f}x** | {med('rps'):.0f} | {med('replayed'):.0f} |")
EOF
