#!/usr/bin/env bash
# bench/render_cost.sh [BUILD_DIR]: what one /metrics and one /api/v1/status cost the daemon's
# event loop, in instructions (valgrind --tool=callgrind: counts that do not depend on the
# machine's load, unlike times).
#
# Starts the drivegated of BUILD_DIR under callgrind with the five simulated drives and the
# configuration of bench/http_load.sh (bench/lib.sh), waits until the drives are online, then
# fetches each path SCRAPES times (a new connection each, as the scraper does) and stops the
# daemon. Prints, per scrape, the instructions of rendering each document (StatusContent's
# status_json() and metrics(), inclusive) and of the whole HTTP exchange (accept, parse, route,
# render, write, close), next to those of one Modbus request for scale.
# Environment: SCRAPES (50), MODBUS (2000: FC03 requests sent, for the per-request figure),
#   SERVER_CPU (0), LOAD_CPU (1), DG_PORT (15080), HTTP_PORT (15081), KEEP (unset; a directory:
#   the callgrind output is copied there).
set -euo pipefail

B=$(realpath "${1:-build-bench}")
SCRAPES=${SCRAPES:-50}
MODBUS=${MODBUS:-2000}
SERVER_CPU=${SERVER_CPU:-0}
LOAD_CPU=${LOAD_CPU:-1}
DG_PORT=${DG_PORT:-15080}
HTTP_PORT=${HTTP_PORT:-15081}
HERE=$(dirname "$(realpath "$0")")
command -v valgrind >/dev/null || { echo "render_cost.sh: needs valgrind" >&2; exit 2; }

# shellcheck source=bench/common.sh
source "$HERE/common.sh"
# shellcheck source=bench/lib.sh
source "$HERE/lib.sh"
bench_workdir render

# start_gateway runs BIN/drivegated: here, a wrapper that runs it under callgrind.
mkdir -p "$W/v/bin"
ln -s "$B/adapters" "$W/v/adapters"
ln -s "$B/bin/drivegate" "$W/v/bin/drivegate"
cat >"$W/v/bin/drivegated" <<EOF
#!/bin/sh
exec valgrind --tool=callgrind --callgrind-out-file=$W/callgrind.out "$B/bin/drivegated" "\$@"
EOF
chmod +x "$W/v/bin/drivegated"

start_gateway "$W/v/bin" dg "[server]
listen = \"127.0.0.1:$DG_PORT\"

[http]
listen = \"127.0.0.1:$HTTP_PORT\""

for _ in 1 2 3; do wait_for_port "$DG_PORT" && break; done
for _ in 1 2 3; do wait_for_port "$HTTP_PORT" && break; done
# Under callgrind the daemon is some 50 times slower: the drives may take more than the 10 s
# mbwrite.py waits for them to come online.
for try in 1 2 3 4 5 6; do
  python3 "$HERE/mbwrite.py" --wait-online "$DG_PORT" "${START[@]}" 2>/dev/null && break
  ((try < 6)) || { echo "render_cost.sh: the drives did not come online" >&2; exit 1; }
done
sleep 2

python3 - "$HTTP_PORT" "$DG_PORT" "$SCRAPES" "$MODBUS" <<'EOF'
import http.client, socket, struct, sys
hport, mport, n, m = (int(a) for a in sys.argv[1:5])
for _ in range(n):
    for path in ("/metrics", "/api/v1/status"):
        c = http.client.HTTPConnection("127.0.0.1", hport, timeout=30)
        c.request("GET", path, headers={"Connection": "close"})
        r = c.getresponse()
        assert r.status == 200 and len(r.read()) > 1000, path
        c.close()
s = socket.create_connection(("127.0.0.1", mport), timeout=30)
for i in range(m):
    s.sendall(struct.pack(">HHHBBHH", i & 0xFFFF, 0, 6, 2, 3, 16, 125))
    want = 9 + 250
    got = b""
    while len(got) < want:
        got += s.recv(want - len(got))
s.close()
EOF

kill -TERM "$GATEWAY_PID"
wait "$GATEWAY_PID" 2>/dev/null || true
[[ -n ${KEEP:-} ]] && cp "$W/callgrind.out" "$KEEP/"

callgrind_annotate --inclusive=yes "$W/callgrind.out" 2>/dev/null >"$W/annotate.txt"
per() {  # per LABEL REGEX DIVISOR
  local ir
  ir=$(grep -E "$2" "$W/annotate.txt" | head -1 | awk '{gsub(",", "", $1); print $1}')
  [[ -n $ir ]] || { printf '%-44s (not found)\n' "$1"; return; }
  printf '%-44s %12d Ir per call (%s in %s calls)\n' "$1" $((ir / $3)) "$ir" "$3"
}
echo "instructions (callgrind), $SCRAPES scrapes of each path, $MODBUS Modbus FC03 16..140 reads:"
per "render /api/v1/status (StatusContent)" 'status_content.cpp:drivegate::StatusContent::status_json' \
  "$SCRAPES"
per "render /metrics (StatusContent)" 'status_content.cpp:drivegate::StatusContent::metrics' "$SCRAPES"
per "HTTP request: route, render, reply (on_read)" 'http_connection.cpp:drivegate::http::HttpConnection::on_read\(' \
  $((2 * SCRAPES))
per "Modbus request: parse, read, reply (on_read)" 'modbus/connection.cpp:drivegate::modbus::Connection::on_read\(' \
  "$MODBUS"
