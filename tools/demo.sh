#!/bin/sh
# Builds drivegate, then runs the demo: a simulated drive for every adapter, the daemon on them,
# Modbus TCP on 127.0.0.1:1502 (or the HOST:PORT given). Ctrl-C stops it.
set -eu
cd "$(dirname "$0")/.."
TARGET=programs tools/build.sh
if [ $# -gt 0 ]; then exec build/bin/drivegate demo --listen "$1"; fi
exec build/bin/drivegate demo
