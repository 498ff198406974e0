#!/usr/bin/env bash
# bench/fleet.sh [BUILD_DIR]: a fleet of gateways on one broker, at several sizes side
# by side in one run.
#
# Each run is tests/e2e/mqtt_fleet_e2e_test.cpp (MqttE2EFleet): N real drivegated processes, each
# with one simulated test-drive (tests/support/test_adapter) on a pty (poll_ms 100, a ramp that
# gives every poll a new speed, min_interval_ms 0: one DDATA per poll), its own edge node id and
# state directory; one mosquitto (/usr/sbin/mosquitto, loopback, no persistence); one Sparkplug host
# (Tahu's codec over MQTT.js, tests/mqtt/peer) that publishes a primary host STATE. Every gateway
# starts at once; LIVE_S seconds of live data; the broker is stopped for OUTAGE_S seconds while
# every ramp goes on; the broker back, every gateway reborn and its store replayed; then a half-open
# outage of HALF_OPEN_S seconds (the gateways reach the broker through the test's proxy, which stops
# forwarding every connection, new ones too, without closing any: tests/support/fault_proxy.h), each
# gateway's time to notice it and what the host lost (goal: nothing) and got twice; one gateway
# killed with -9 and restarted. The run also asserts what the host must see (every change, in order,
# the will's bdSeq): a failed assertion fails the bench.
#
# The test writes its figures (births per second, frame -> host latency, replay rate, CPU and
# memory of the gateways, the broker and the host) to a report file; this script puts the runs
# side by side. What each figure is and how it is taken: docs/performance.md.
#
# Sizes run in SIZES order, each with the default replay_per_s (500), then the largest again with
# FAST_REPLAY (replay_per_s 5000): what limits the replay when a gateway does not.
#
# Environment: SIZES ("10 20 40"), LIVE_S (30), OUTAGE_S (30), HALF_OPEN_S (30; 0: skip),
#   FAST_REPLAY (5000; 0: skip), LOAD_MAX (1.5), LOAD_WAIT (600 s).
set -euo pipefail

B=$(realpath "${1:-build}")
TEST=$B/tests/e2e/mqtt_fleet_e2e_test
HERE=$(dirname "$(realpath "$0")")
SIZES=${SIZES:-"10 20 40"}
LIVE_S=${LIVE_S:-30}
OUTAGE_S=${OUTAGE_S:-30}
HALF_OPEN_S=${HALF_OPEN_S:-30}
FAST_REPLAY=${FAST_REPLAY:-5000}
LOAD_MAX=${LOAD_MAX:-1.5}
LOAD_WAIT=${LOAD_WAIT:-600}

[[ -x $TEST ]] || {
  echo "fleet.sh: $TEST missing (build with -DDRIVEGATE_TESTS=ON)" >&2
  exit 2
}

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir fleet

RUNS=()
run() {  # run NAME GATEWAYS [REPLAY_PER_S]
  local name=$1 report=$W/$1.txt
  wait_load
  echo "fleet.sh: $name: $2 gateways, replay_per_s ${3:-500}, load $LOAD" >&2
  if ! DRIVEGATE_FLEET_GATEWAYS=$2 DRIVEGATE_FLEET_LIVE_S=$LIVE_S DRIVEGATE_FLEET_OUTAGE_S=$OUTAGE_S \
    DRIVEGATE_FLEET_HALF_OPEN_S=$HALF_OPEN_S \
    DRIVEGATE_FLEET_REPLAY_PER_S=${3:-0} DRIVEGATE_FLEET_REPORT=$report \
    "$TEST" --gtest_filter='MqttE2EFleet.*' >"$W/$name.log" 2>&1; then
    grep -A 12 -E '(Failure|exception)' "$W/$name.log" | head -n 80 >&2 || true
    tail -n 20 "$W/$name.log" >&2
    echo "fleet.sh: $name failed (its assertions above)" >&2
    exit 1
  fi
  # LOAD ends in "(!)" when the machine never got quiet: a figure of its own.
  echo "load_before ${LOAD%(!)}" >>"$report"
  [[ $LOAD == *'(!)' ]] && echo "load_over_max 1" >>"$report"
  RUNS+=("$name")
}

for n in $SIZES; do run "n$n" "$n"; done
largest=$(tr ' ' '\n' <<<"$SIZES" | sort -n | tail -n 1)
if ((FAST_REPLAY > 0)); then run "n$largest-fast" "$largest" "$FAST_REPLAY"; fi

# The table: one column per run, one row per figure, in the order the test reports them.
python3 - "$W" "${RUNS[@]}" <<'EOF'
import sys
w, runs = sys.argv[1], sys.argv[2:]
cols, keys = {}, []
for r in runs:
    cols[r] = {}
    for line in open(f"{w}/{r}.txt"):
        k, v = line.split()
        cols[r][k] = float(v)
        if k not in keys:
            keys.append(k)
print("| figure | " + " | ".join(runs) + " |")
print("|---" * (len(runs) + 1) + "|")
for k in keys:
    cells = []
    for r in runs:
        v = cols[r].get(k)
        cells.append("" if v is None else f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}")
    print(f"| {k} | " + " | ".join(cells) + " |")
EOF
