#!/bin/sh
# Builds drivegate in build/ (or $BUILD_DIR), installing missing Debian packages first.
# Extra arguments go to cmake's configure step, e.g. -DDRIVEGATE_SANITIZE=address,undefined.
# TARGET=programs builds only the daemon, the CLI and the plugins.
set -eu
cd "$(dirname "$0")/.."
tools/deps.sh
build="${BUILD_DIR:-build}"
# Relative paths in ccache's keys: a second clone (CI's) reuses this one's compiled objects.
export CCACHE_BASEDIR="$PWD"
cmake -S . -B "$build" "$@" >/dev/null
cmake --build "$build" -j"$(nproc)" ${TARGET:+--target "$TARGET"}
