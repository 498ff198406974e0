#!/usr/bin/env bash
# bench/history.sh [BUILD_DIR]: what the history (docs/audit.md) costs, side by side with it off
# in one run: 32 buses x 4 simulated ed3100 drives, the daemon with [history] as
# shipped (2000 events, 600 s of trends) and with `events = 0, trend_seconds = 0`, alternately
# ROUNDS times on the same simulators. In each window of DURATION s: a writer sends WRITES_PER_S
# distinct setpoint writes spread over the 128 drives (each one an audit record), while
# dg-loadgen keeps one connection of FC04 reads (the common block) going for its p99.
# Prints per setup: RSS, the daemon's CPU (% of one core), the Modbus p99 and p50, and the
# history's bytes and entries as /metrics and /api/v1/events say.
# Environment: ROUNDS (2), DURATION (20), WRITES_PER_S (20), PORT (15090), HTTP_PORT (15091).
set -euo pipefail
B=$(realpath "${1:-build-bench}")
BIN=$B/bin
PLUGINS=$B/adapters
HERE=$(dirname "$(realpath "$0")")
ROUNDS=${ROUNDS:-2}
DURATION=${DURATION:-20}
WRITES_PER_S=${WRITES_PER_S:-20}
PORT=${PORT:-15090}
HTTP_PORT=${HTTP_PORT:-15091}
# shellcheck source=bench/common.sh
source "$HERE/common.sh"
bench_workdir history

ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }

base=$W/base.toml
{ echo "[server]"; echo "listen = \"127.0.0.1:$PORT\""
  echo "[http]"; echo "listen = \"127.0.0.1:$HTTP_PORT\""; echo "requests_per_s = 0"; } >"$base"
for b in $(seq 32); do
  "$BIN/drivegate" sim ed3100 --plugin-dir "$PLUGINS" --link "$W/bus$b" --address 1 --address 2 \
    --address 3 --address 4 </dev/null >/dev/null 2>&1 &
  PIDS+=($!)
  wait_for_path "$W/bus$b" || true
  { echo "[[bus]]"; echo "name = \"bus$b\""; echo "port = \"$W/bus$b\""; } >>"$base"
  for a in 1 2 3 4; do
    u=$(((b - 1) * 4 + a))
    { echo "[[device]]"; echo "name = \"d$u\""; echo "bus = \"bus$b\""; echo "adapter = \"ed3100\""
      echo "unit_id = $u"; echo "address = $a"; } >>"$base"
  done
done
{ cat "$base"; echo "[history]"; echo "events = 2000"; echo "trend_seconds = 600"; } >"$W/on.toml"
{ cat "$base"; echo "[history]"; echo "events = 0"; echo "trend_seconds = 0"; } >"$W/off.toml"

measure() {  # measure NAME
  local name=$1
  "$BIN/drivegated" --config "$W/$name.toml" --plugin-dir "$PLUGINS" --log-level warn \
    >"$W/$name.log" 2>&1 &
  local dg=$!
  PIDS+=("$dg")
  wait_for_port "$PORT"
  python3 "$HERE/mbwrite.py" --wait-online "$PORT" 1:1=0 128:1=0 >/dev/null
  sleep 3
  python3 - "$PORT" "$DURATION" "$WRITES_PER_S" >"$W/writer.out" 2>&1 <<'PY' &
import socket, struct, sys, time
port, secs, rate = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
s = socket.create_connection(("127.0.0.1", port))
tid, end, n = 0, time.monotonic() + secs, 0
while time.monotonic() < end:
    unit = n % 128 + 1
    rpm = 100 + (n // 128) % 1000  # never the same value twice in a row at one drive
    tid = (tid + 1) & 0xFFFF
    # FC16 to setpoint_rpm (holding 1): Modbus Application Protocol 6.12.
    pdu = struct.pack(">BHHBH", 16, 1, 1, 2, rpm)
    s.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu)
    head = s.recv(7)
    s.recv(struct.unpack(">H", head[4:6])[0] - 1)
    n += 1
    time.sleep(1.0 / rate)
print(n)
PY
  local writer=$!
  local t0 t1 hz rss load
  hz=$(getconf CLK_TCK)
  t0=$(ticks "$dg")
  load=$("$BIN/dg-loadgen" --port "$PORT" --unit 1 --connections 1 --duration "$DURATION" \
    --large 4:0:19 --small 4:0:19)
  t1=$(ticks "$dg")
  wait "$writer" || true
  rss=$(awk '/VmRSS/ {print $2}' "/proc/$dg/status")
  local metrics events
  metrics=$(python3 -c "import urllib.request as u; print(u.urlopen('http://127.0.0.1:$HTTP_PORT/metrics').read().decode())")
  events=$(python3 -c "import json, urllib.request as u; d = json.load(u.urlopen('http://127.0.0.1:$HTTP_PORT/api/v1/events?limit=1000')); print(len(d['events']))")
  python3 - "$name" "$rss" "$t0" "$t1" "$hz" "$DURATION" "$load" "$events" "$(cat "$W/writer.out")" <<PY
import sys
name, rss, t0, t1, hz, secs, load, events, writes = sys.argv[1:]
kv = dict(p.split("=") for p in load.split())
cpu = 100 * (int(t1) - int(t0)) / int(hz) / float(secs)
hist = [l.split()[-1] for l in """$metrics""".splitlines() if l.startswith("drivegate_history_bytes ")]
print(f"| {name} | {int(rss) / 1024:.1f} | {cpu:.2f} | {kv['p50_us']} | {kv['p99_us']} | "
      f"{writes.strip()} | {events} | {hist[0] if hist else '-'} |")
PY
  kill "$dg"; wait "$dg" 2>/dev/null || true
}

echo "| history | RSS MiB | CPU % (of one core) | Modbus p50 us | Modbus p99 us | writes | entries served | history bytes |"
echo "|---|---|---|---|---|---|---|---|"
for _ in $(seq "$ROUNDS"); do
  measure on
  measure off
done
