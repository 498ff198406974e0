#!/bin/sh
# Builds drivegate's programs, then runs the demo: a simulated drive for every adapter, the daemon
# on them, Modbus TCP on 127.0.0.1:1502 (or the HOST:PORT given). Ctrl-C stops it.
# Installs only what the programs need (tools/deps.sh build), none of the tests' tools.
set -eu
cd "$(dirname "$0")/.."
DEPS="build" TARGET=programs tools/build.sh
if [ $# -gt 0 ]; then exec build/bin/drivegate demo --listen "$1"; fi
exec build/bin/drivegate demo
