#!/bin/sh
# Installs the Debian 12 packages drivegate builds and tests with, if any is missing.
# Usage: tools/deps.sh [extra-package...]
set -eu
packages="build-essential cmake pkg-config ccache libboost-dev libmodbus-dev libtomlplusplus-dev
libspdlog-dev libsystemd-dev libssl-dev libgtest-dev libgmock-dev mbpoll openssl
python3-pymodbus python3-serial-asyncio ser2net chromium prometheus tshark $*"
missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "tools/deps.sh: installing$missing" >&2
if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
