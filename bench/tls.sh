#!/usr/bin/env bash
# bench/tls.sh [BUILD_DIR]: Modbus/TCP Security, a TLS listener against the plaintext listener of
# the same drivegated, in the same run.
#
# Makes test certificates (tests/support/make_certs.sh) in a temporary directory and starts ONE
# drivegated, pinned to CPU $SERVER_CPU, polling the same five simulated drives as bench/run.sh
# (bench/lib.sh), with two listeners: plaintext (access maintain) and TLS (client certificate
# required, roles viewer/operator/engineer). The load generator (and the simulators) run on CPU
# $LOAD_CPU. Then:
#   1. for ROUNDS rounds, for N in $CONNS persistent connections: dg-loadgen against the plaintext
#      listener and against the TLS listener (handshake at connect, not measured), the same
#      requests as bench/run.sh (FC03 16..140 alternating with FC04 0..18, unit 2); the order
#      alternates (plaintext first in odd rounds, TLS first in even ones). Medians, TLS / plain.
#   2. for ROUNDS rounds, for C in $HS_CONNS: dg-loadgen --handshakes: each of C parallel slots
#      connects, makes a full TLS handshake with the client certificate, reads the common block
#      (FC04 0..18) once and closes, again and again; then the same with --resume (each new
#      connection offers the session ticket of the one before). Medians.
# The client certificate is $CERT (engineer: role maintain; the reads need only read access).
# Environment: ROUNDS (4), DURATION (3 s per run), WARMUP (0.5 s), CONNS ("1 8 64"),
#   HS_CONNS ("1 8"), HS_RESUME (1: also measure resumed handshakes), TLS_MAX ("": TLS 1.3 as
#   negotiated; "1.2": TLS 1.2 at most), SERVER_CPU (0), LOAD_CPU (1), LARGE (3:16:125),
#   SMALL (4:0:19), UNIT (2), CERT (engineer), PLAIN_PORT (15060), TLS_PORT (15061).
set -euo pipefail

B=$(realpath "${1:-build-bench}")
BIN=$B/bin
ROUNDS=${ROUNDS:-4}
DURATION=${DURATION:-3}
WARMUP=${WARMUP:-0.5}
CONNS=${CONNS:-"1 8 64"}
HS_CONNS=${HS_CONNS:-"1 8"}
HS_RESUME=${HS_RESUME:-1}
TLS_MAX=${TLS_MAX:-}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
LARGE=${LARGE:-3:16:125}
SMALL=${SMALL:-4:0:19}
UNIT=${UNIT:-2}
CERT=${CERT:-engineer}
PLAIN_PORT=${PLAIN_PORT:-15060}
TLS_PORT=${TLS_PORT:-15061}
HERE=$(dirname "$(realpath "$0")")

for f in drivegated drivegate dg-loadgen; do
  [[ -e $BIN/$f ]] || { echo "tls.sh: $BIN/$f missing (build with -DDRIVEGATE_BENCH=ON)" >&2; exit 2; }
done
((ROUNDS % 2 == 0)) || echo "tls.sh: ROUNDS=$ROUNDS is odd: plaintext goes first once more" >&2

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
# shellcheck source=bench/lib.sh
source "$HERE/lib.sh"
bench_workdir tls

C=$W/certs
sh "$HERE/../tests/support/make_certs.sh" "$C" >/dev/null
TLS_ARGS=(--tls-ca "$C/ca.pem" --tls-cert "$C/$CERT.pem" --tls-key "$C/$CERT.key")
[[ -n $TLS_MAX ]] && TLS_ARGS+=(--tls-max "$TLS_MAX")

start_gateway "$BIN" dg "[server]
max_clients = 256

[[listener]]
address = \"127.0.0.1:$PLAIN_PORT\"
access = \"maintain\"

[[listener]]
address = \"127.0.0.1:$TLS_PORT\"
tls = { cert = \"$C/server.pem\", key = \"$C/server.key\", ca = \"$C/ca.pem\" }
roles = { viewer = \"read\", operator = \"operate\", engineer = \"maintain\" }"
DG_PID=$GATEWAY_PID

# Both listeners are bound before either accepts; probing only the plaintext one keeps a
# handshake-less connection out of the TLS listener's log.
wait_for_port "$PLAIN_PORT" || { cat "$W"/dg/drivegated.log >&2; exit 1; }
python3 "$HERE/mbwrite.py" --wait-online "$PLAIN_PORT" "${START[@]}"
sleep 2

COMMON=(--pid "$DG_PID" --duration "$DURATION" --warmup "$WARMUP" --unit "$UNIT" --small "$SMALL"
        --self-cpu)

# failed WHAT: a dg-loadgen run failed; its messages, and the daemon's, before the directory goes.
failed() {
  echo "tls.sh: dg-loadgen failed ($1):" >&2
  tail -5 "$W/loadgen.err" >&2
  kill -0 "$DG_PID" 2>/dev/null || echo "tls.sh: drivegated (pid $DG_PID) is gone" >&2
  tail -5 "$W/dg/drivegated.log" >&2
  exit 1
}

load() {  # load SIDE N ROUND
  local out args=()
  if [[ $1 == tls ]]; then
    args=(--port "$TLS_PORT" "${TLS_ARGS[@]}")
  else
    args=(--port "$PLAIN_PORT")
  fi
  out=$(taskset -c "$LOAD_CPU" "$BIN/dg-loadgen" "${args[@]}" "${COMMON[@]}" --connections "$2" \
    --large "$LARGE" 2>>"$W/loadgen.err") || failed "$1 N=$2"
  echo "persistent $1 $2 $3 $out" | tee -a "$W/results.txt" >&2
}

handshakes() {  # handshakes MODE C ROUND
  local out extra=()
  [[ $1 == resumed ]] && extra=(--resume)
  out=$(taskset -c "$LOAD_CPU" "$BIN/dg-loadgen" --port "$TLS_PORT" "${TLS_ARGS[@]}" \
    "${COMMON[@]}" --handshakes "${extra[@]}" --connections "$2" 2>>"$W/loadgen.err") ||
    failed "handshakes $1 C=$2"
  echo "handshake $1 $2 $3 $out" | tee -a "$W/results.txt" >&2
}

for round in $(seq "$ROUNDS"); do
  for n in $CONNS; do
    if ((round % 2 == 1)); then
      load plain "$n" "$round"
      load tls "$n" "$round"
    else
      load tls "$n" "$round"
      load plain "$n" "$round"
    fi
  done
done
for round in $(seq "$ROUNDS"); do
  for c in $HS_CONNS; do
    handshakes full "$c" "$round"
    ((HS_RESUME)) && handshakes resumed "$c" "$round"
  done
done

echo
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs," \
  "$(uname -sr), $(openssl version | cut -d' ' -f1-2); server on CPU $SERVER_CPU, load generator" \
  "on CPU $LOAD_CPU; $ROUNDS rounds x ${DURATION}s; large=$LARGE small=$SMALL unit=$UNIT;" \
  "client certificate $CERT"
echo "negotiated (loadgen runs):"; sort "$W/loadgen.err" | uniq -c | sed "s/^ */  /"
python3 "$HERE/tls_summary.py" "$W/results.txt"
grep -i "error\|critical\|warn" "$W"/dg/drivegated.log | grep -v "lets every address" | head -5 || true
