#!/usr/bin/env bash
# bench/flood.sh [BUILD_DIR]: "no class of client can starve another", measured. A
# plaintext PLC's Modbus latency while another client floods the daemon, with the limits on and
# with them off, side by side in one run.
#
# Starts TWO drivegated, both pinned to CPU $SERVER_CPU, each polling five simulated drives
# (bench/lib.sh) and serving a plaintext listener, a TLS listener and [http]:
#   limited    the defaults: tls_handshakes_per_s = 5 (bursts of 10), [http] requests_per_s = 20
#   unlimited  tls_handshakes_per_s = 0, requests_per_s = 0: what the daemon did before the limits
# For ROUNDS rounds, for each daemon, three phases of DURATION s, each measured by dg-loadgen with
# one connection on the plaintext listener (FC03 16..140 alternating with FC04 0..18, unit 2):
#   quiet      nothing else
#   tls-flood  dg-loadgen --handshakes --flood with $FLOOD_SLOTS slots, all from 127.0.0.1, on the
#              TLS listener: connect, full handshake with a client certificate, one read, close,
#              again at once (a refused connection: again at once)
#   tls-decoy  (limited only) the same flood on a third daemon's TLS listener, that daemon on the
#              clients' CPU: what the flood costs the machine, not the daemon under test
#   http       $HAMMERS dg-scraper clients from 127.0.0.1, each fetching /metrics and
#              /api/v1/status $HAMMER_RATE times a second on kept-alive connections
#   history    $PULLERS dg-scraper clients, each from its own address (127.0.0.2, .3, ...),
#              fetching the history's largest page (/api/v1/events?limit=1000, the history first
#              filled with $FILL distinct setpoint writes: since the history folds a client's
#              flood, a few KB; the 330 KB page needs plant events) $PULL_RATE times a second on
#              a kept-alive connection
# With BASELINE_BIN (another build's bin directory, e.g. main's), a third daemon "baseline" of
# that build with the defaults, measured in the same rounds: the same phases before and after.
# The load generators and the simulators run on CPU $LOAD_CPU, the flooding and hammering
# clients at nice 19 there, so that what is measured is what the daemon does with the load, not
# the measuring client waiting for its own CPU. Prints the medians and each phase's p99 over its
# daemon's quiet p99.
# Environment: ROUNDS (4), DURATION (4 s), FLOOD_SLOTS (8), HAMMERS (12), HAMMER_RATE (200),
#   PULLERS (16), PULL_RATE (50), FILL (1100), HS_RATE (the limited daemon's tls_handshakes_per_s;
#   its default when unset), BASELINE_BIN, SERVER_CPU (0), LOAD_CPU (1).
set -euo pipefail

B=$(realpath "${1:-build-bench}")
BIN=$B/bin
ROUNDS=${ROUNDS:-4}
DURATION=${DURATION:-4}
FLOOD_SLOTS=${FLOOD_SLOTS:-8}
HAMMERS=${HAMMERS:-12}
HAMMER_RATE=${HAMMER_RATE:-200}
PULLERS=${PULLERS:-16}
PULL_RATE=${PULL_RATE:-50}
FILL=${FILL:-1100}
BASELINE_BIN=${BASELINE_BIN:+$(realpath "$BASELINE_BIN")}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
HERE=$(dirname "$(realpath "$0")")
for f in drivegated drivegate dg-loadgen dg-scraper; do
  [[ -e $BIN/$f ]] || { echo "flood.sh: $BIN/$f missing (build with -DDRIVEGATE_BENCH=ON)" >&2; exit 2; }
done

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
# shellcheck source=bench/lib.sh
source "$HERE/lib.sh"
bench_workdir flood

C=$W/certs
sh "$HERE/../tests/support/make_certs.sh" "$C" >/dev/null
TLS_ARGS=(--tls-ca "$C/ca.pem" --tls-cert "$C/engineer.pem" --tls-key "$C/engineer.key")

declare -A PLAIN TLS HTTP PID
TAGS=(limited unlimited)
[[ -n $BASELINE_BIN ]] && TAGS+=(baseline)
port=15300
for tag in "${TAGS[@]}"; do
  PLAIN[$tag]=$port TLS[$tag]=$((port + 1)) HTTP[$tag]=$((port + 2))
  port=$((port + 10))
  hs="" rq=""
  [[ -n ${HS_RATE:-} ]] && hs="tls_handshakes_per_s = $HS_RATE"
  if [[ $tag == unlimited ]]; then
    hs="tls_handshakes_per_s = 0"
    rq="requests_per_s = 0"
  fi
  bin=$BIN
  [[ $tag == baseline ]] && bin=$BASELINE_BIN
  start_gateway "$bin" "$tag" "[server]
max_clients = 64

[http]
listen = \"127.0.0.1:${HTTP[$tag]}\"
$rq

[[listener]]
address = \"127.0.0.1:${PLAIN[$tag]}\"
access = \"maintain\"

[[listener]]
address = \"127.0.0.1:${TLS[$tag]}\"
tls = { cert = \"$C/server.pem\", key = \"$C/server.key\", ca = \"$C/ca.pem\" }
roles = { engineer = \"maintain\" }
$hs"
  PID[$tag]=$GATEWAY_PID
done
# The decoy: a third daemon, with the limits, on the clients' CPU. Flooding its TLS listener costs
# the machine what a flood costs (the flooding client, the kernel's connects and closes on
# loopback, a CPU busy beside the server's) without a byte of it reaching the daemon under test:
# the "tls-decoy" phase, the share of a tls-flood figure that is not the daemon's doing.
PLAIN[decoy]=$port TLS[decoy]=$((port + 1)) HTTP[decoy]=$((port + 2))
SERVER_CPU=$LOAD_CPU start_gateway "$BIN" decoy "[[listener]]
address = \"127.0.0.1:${PLAIN[decoy]}\"
access = \"maintain\"

[[listener]]
address = \"127.0.0.1:${TLS[decoy]}\"
tls = { cert = \"$C/server.pem\", key = \"$C/server.key\", ca = \"$C/ca.pem\" }
roles = { engineer = \"maintain\" }"
for tag in "${TAGS[@]}" decoy; do
  wait_for_port "${PLAIN[$tag]}" || { cat "$W/$tag/drivegated.log" >&2; exit 1; }
  python3 "$HERE/mbwrite.py" --wait-online "${PLAIN[$tag]}" "${START[@]}"
done

# fill_history PORT: $FILL setpoint writes, each a value its drive had not just before, spread
# over the five running drives (one connection each): as many command records in the history.
fill_history() {
  python3 - "$1" "$FILL" <<'PY'
import socket, struct, sys, threading
port, total = int(sys.argv[1]), int(sys.argv[2])
def writer(unit, n):
    s = socket.create_connection(("127.0.0.1", port))
    for i in range(n):
        # FC06 to setpoint_rpm (holding 1): Modbus Application Protocol 6.6.
        pdu = struct.pack(">BHH", 6, 1, 600 + i % 500)
        s.sendall(struct.pack(">HHHB", i & 0xFFFF, 0, len(pdu) + 1, unit) + pdu)
        head = s.recv(7, socket.MSG_WAITALL)
        s.recv(struct.unpack(">H", head[4:6])[0] - 1, socket.MSG_WAITALL)
threads = [threading.Thread(target=writer, args=(u, total // 5 + 1)) for u in range(1, 6)]
for t in threads: t.start()
for t in threads: t.join()
PY
}
for tag in "${TAGS[@]}"; do
  fill_history "${PLAIN[$tag]}"
  bytes=$(curl -s "http://127.0.0.1:${HTTP[$tag]}/api/v1/events?limit=1000" | wc -c)
  echo "flood.sh: $tag: the history's largest page is $bytes bytes" >&2
done
sleep 2

measure() {  # measure TAG PHASE ROUND: the plaintext client's line, into results.txt
  local out
  out=$(taskset -c "$LOAD_CPU" "$BIN/dg-loadgen" --port "${PLAIN[$1]}" --pid "${PID[$1]}" \
    --duration "$DURATION" --warmup 0.5 --unit 2 --small 4:0:19 --large 3:16:125 \
    --connections 1 2>>"$W/loadgen.err") || {
    echo "flood.sh: dg-loadgen failed ($1 $2)" >&2; tail -5 "$W/loadgen.err" >&2
    tail -5 "$W/$1/drivegated.log" >&2; exit 1; }
  echo "$1 $2 $3 $out" | tee -a "$W/results.txt" >&2
}

flood() {  # flood TARGET_TAG: a handshake flood on that daemon's TLS listener, in the background
  taskset -c "$LOAD_CPU" nice -n 19 "$BIN/dg-loadgen" --port "${TLS[$1]}" "${TLS_ARGS[@]}" \
    --handshakes --flood --connections "$FLOOD_SLOTS" --duration "$((DURATION + 2))" --warmup 0 \
    >>"$W/flood.out" 2>>"$W/flood.err" &
  FLOOD_PID=$!
  sleep 0.5
}

for round in $(seq "$ROUNDS"); do
  for tag in "${TAGS[@]}"; do
    measure "$tag" quiet "$round"

    flood "$tag"
    measure "$tag" tls-flood "$round"
    wait "$FLOOD_PID" || true

    if [[ $tag == limited ]]; then
      flood decoy
      measure "$tag" tls-decoy "$round"
      wait "$FLOOD_PID" || true
    fi

    hammers=()
    for _ in $(seq "$HAMMERS"); do
      taskset -c "$LOAD_CPU" nice -n 19 "$BIN/dg-scraper" "${HTTP[$tag]}" "$HAMMER_RATE" "$((DURATION + 2))" \
        "$W/hammer.out" --keep-alive >/dev/null 2>>"$W/hammer.err" &
      hammers+=($!)
    done
    sleep 0.5
    measure "$tag" http "$round"
    # Paced, a hammer would still be working through its schedule long after: stopped here.
    kill "${hammers[@]}" 2>/dev/null || true
    wait "${hammers[@]}" 2>/dev/null || true

    pullers=()
    for i in $(seq "$PULLERS"); do
      taskset -c "$LOAD_CPU" nice -n 19 "$BIN/dg-scraper" "${HTTP[$tag]}" "$PULL_RATE" \
        "$((DURATION + 2))" "$W/pull-$tag.out" --keep-alive --path "/api/v1/events?limit=1000" \
        --from "127.0.0.$((1 + i))" >/dev/null 2>>"$W/pull.err" &
      pullers+=($!)
    done
    sleep 0.5
    measure "$tag" history "$round"
    kill "${pullers[@]}" 2>/dev/null || true
    wait "${pullers[@]}" 2>/dev/null || true
  done
done

echo
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr); both daemons on CPU $SERVER_CPU, clients on CPU $LOAD_CPU; $ROUNDS rounds x" \
  "${DURATION}s; flood: $FLOOD_SLOTS handshake slots; http: $HAMMERS clients x $HAMMER_RATE/s;" \
  "history: $PULLERS addresses x $PULL_RATE/s; baseline: ${BASELINE_BIN:-none}"
python3 - "$W/results.txt" <<'EOF'
import statistics, sys
rows = {}
for line in open(sys.argv[1]):
    tag, phase, _round, *kv = line.split()
    d = dict(x.split("=", 1) for x in kv)
    rows.setdefault((tag, phase), []).append((float(d["p50_us"]), float(d["p99_us"]), float(d["rps"])))
print("| daemon | phase | Modbus p50 | p99 | p99 / quiet p99 | requests/s |")
print("|---|---|---|---|---|---|")
for tag in ("limited", "unlimited", "baseline"):
    if (tag, "quiet") not in rows:
        continue
    quiet = statistics.median(r[1] for r in rows[(tag, "quiet")])
    for phase in ("quiet", "tls-flood", "tls-decoy", "http", "history"):
        if (tag, phase) not in rows:
            continue
        r = rows[(tag, phase)]
        p50 = statistics.median(x[0] for x in r)
        p99 = statistics.median(x[1] for x in r)
        rps = statistics.median(x[2] for x in r)
        print(f"| {tag} | {phase} | {p50 / 1000:.3f} ms | {p99 / 1000:.3f} ms | {p99 / quiet:.2f}x | {rps:.0f} |")
EOF
echo "handshake floods (dg-loadgen --flood, per run, in order: limited, decoy, unlimited):"
sed -n 's/.*handshakes=\([0-9]*\) errors=\([0-9]*\).*/  \1 completed, \2 refused/p' "$W/flood.out" | head -6
echo "history pulls (dg-scraper, per daemon: pages, p50 and p99 of a page):"
for tag in "${TAGS[@]}"; do
  [[ -e $W/pull-$tag.out ]] || continue
  awk -v t="$tag" '{for (i = 2; i <= NF; i++) {split($i, kv, "="); v[kv[1]] = kv[2]}
    n += v["requests"]; p50 = v["p50_ms"]; p99 = v["p99_ms"]}
    END {printf "  %s: %d pages, last puller p50 %s ms, p99 %s ms\n", t, n, p50, p99}' \
    "$W/pull-$tag.out"
done
echo "daemons' limit counters:"
for tag in "${TAGS[@]}"; do
  curl -s "http://127.0.0.1:${HTTP[$tag]}/metrics" 2>/dev/null |
    grep -E "^drivegate_(modbus_tls_handshakes_limited_total|http_requests_paced_total)" |
    sed "s/^/  $tag: /" || true
done
