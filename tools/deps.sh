#!/bin/sh
# Installs the Debian 12 packages drivegate builds and tests with, if any is missing, then the
# npm packages of the end-to-end tests' Sparkplug peer (tests/mqtt/peer) if they are missing or
# older than its package-lock.json.
# Usage: tools/deps.sh [extra-package...]
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
packages="build-essential cmake pkg-config ccache libboost-dev libmodbus-dev libtomlplusplus-dev
libspdlog-dev libsystemd-dev libssl-dev libgtest-dev libgmock-dev mbpoll openssl
python3-pymodbus python3-serial-asyncio ser2net chromium prometheus tshark
mosquitto mosquitto-clients libmosquitto-dev protobuf-compiler libprotobuf-dev $*"
# Node.js runs the Sparkplug peer; Debian's only where no node is on PATH already.
command -v node >/dev/null 2>&1 || packages="$packages nodejs npm"
missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "tools/deps.sh: installing$missing" >&2
  if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

# The peer's node_modules, exactly as package-lock.json pins them (npm writes
# node_modules/.package-lock.json at each install).
peer="$root/tests/mqtt/peer"
stamp="$peer/node_modules/.package-lock.json"
if [ ! -f "$stamp" ] || [ -n "$(find "$peer/package-lock.json" -newer "$stamp")" ]; then
  log=$(mktemp)
  if ! (cd "$peer" && npm ci --no-audit --no-fund) >"$log" 2>&1; then
    cat "$log" >&2
    rm -f "$log"
    echo "tools/deps.sh: npm ci failed in tests/mqtt/peer" >&2
    exit 1
  fi
  rm -f "$log"
fi
