#!/bin/sh
# Builds drivegate in build/ (or $BUILD_DIR), installing missing Debian packages first.
# Extra arguments go to cmake's configure step, e.g. -DDRIVEGATE_SANITIZE=address,undefined.
# TARGET=programs builds only the daemon, the CLI and the plugins.
# DEPS=build installs only what the programs need (tools/deps.sh build) and, in a build tree
# configured for the first time, leaves the tests out of it (they need GoogleTest); DEPS=test,
# the default, installs everything the tests use too.
set -eu
cd "$(dirname "$0")/.."
deps="${DEPS:-test}"
tools/deps.sh "$deps"
build="${BUILD_DIR:-build}"
# A build tree that has the tests keeps them (tools/test.sh made it, and GoogleTest is there).
if [ "$deps" = build ] && [ ! -f "$build/CMakeCache.txt" ]; then
  set -- -DDRIVEGATE_TESTS=OFF "$@"
fi
# Relative paths in ccache's keys: a second clone (CI's) reuses this one's compiled objects.
export CCACHE_BASEDIR="$PWD"
cmake -S . -B "$build" "$@" >/dev/null
cmake --build "$build" -j"$(nproc)" ${TARGET:+--target "$TARGET"}
