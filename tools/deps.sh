#!/bin/sh
# Installs the Debian 12 packages drivegate needs, if any is missing, for one of two purposes:
#
#   tools/deps.sh build [extra-package...]   building the programs and running them: compiler,
#                                            libraries, and mbpoll, the demo's Modbus client
#   tools/deps.sh test [extra-package...]    the above, plus what the tests build with and the
#                                            programs they drive (GoogleTest, chromium,
#                                            prometheus, tshark, mosquitto, ser2net, pymodbus,
#                                            openssl, Node.js), and the npm packages of the
#                                            end-to-end tests' Sparkplug peer (tests/mqtt/peer)
#   tools/deps.sh ci [extra-package...]      the above, plus what only CI runs: clang-14 for the
#                                            fuzzers (tools/fuzz.sh) and clang-tidy-14
#                                            (tools/tidy.sh)
#   tools/deps.sh [extra-package...]         the same as `test`
#
# Each list is written once, here; tools/demo.sh installs `build`, tools/test.sh `test`.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)

# What `cmake --build build --target programs` needs, and the client the demo's hints use.
build_packages="build-essential cmake pkg-config ccache libboost-dev libmodbus-dev
libtomlplusplus-dev libspdlog-dev libsystemd-dev libssl-dev libmosquitto-dev protobuf-compiler
libprotobuf-dev mbpoll"
# The tests' own: GoogleTest, and the programs the end-to-end tests run beside the daemon.
test_packages="libgtest-dev libgmock-dev openssl python3-pymodbus python3-serial-asyncio ser2net socat
chromium prometheus tshark mosquitto mosquitto-clients"
# CI's own: the fuzzers' compiler and runtime, and the linter.
ci_packages="clang-14 libclang-rt-14-dev clang-tidy-14"

profile="test"
case "${1:-}" in
  build | test | ci)
    profile=$1
    shift
    ;;
esac

packages="$build_packages $*"
[ "$profile" = ci ] && packages="$packages $ci_packages"
if [ "$profile" != build ]; then
  packages="$packages $test_packages"
  # Node.js runs the Sparkplug peer; Debian's only where no node is on PATH already.
  command -v node >/dev/null 2>&1 || packages="$packages nodejs npm"
fi

missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "tools/deps.sh: installing$missing" >&2
  if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
  $sudo apt-get update -qq
  # shellcheck disable=SC2086 # $missing is a list of package names
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

[ "$profile" != build ] || exit 0

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
