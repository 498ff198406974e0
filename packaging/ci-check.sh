#!/bin/bash
# The package's whole life on a fresh Debian 12 machine, as root (CI calls it from .ci/run):
#
#   packaging/ci-check.sh
#
#  1. installs the build dependencies (debian/control) and the tools below with apt-get;
#  2. builds the package (packaging/build-deb.sh) and runs lintian on it: errors and warnings fail;
#  3. installs it with `apt-get install ./drivegate_*.deb` and checks what it installed;
#  4. `systemd-analyze verify` of the installed unit must print nothing, and
#     `systemd-analyze security --offline=yes` must rate its exposure 2.0 or less;
#  5. runs the installed drivegated as user drivegate (setpriv: no systemd as PID 1 here)
#     against one simulator per adapter, started with the installed `drivegate sim` on ptys
#     linked where the installed example configuration, adapted, names its ports; reads every
#     unit's status register with mbpoll and writes and reads back a setpoint; stops it with
#     SIGTERM, which must exit 0;
#  6. purges the package and checks nothing of it is left but the system user and group.
#
# Ends with "ci-check: N passed, M failed" and exits non-zero when a check failed.
set -uo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
port=15020 # a high port: the check runs as an unprivileged user without CAP_NET_BIND_SERVICE
passed=0
failed=0

pass() {
    echo "ci-check: ok: $*"
    passed=$((passed + 1))
}
fail() {
    echo "ci-check: FAILED: $*" >&2
    failed=$((failed + 1))
}
check() { # check "what" command...
    local what="$1"
    shift
    if "$@"; then pass "$what"; else fail "$what"; fi
}
finish() {
    echo "ci-check: $passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit
}
die() {
    fail "$*"
    finish
}

[ "$(id -u)" -eq 0 ] || die "must run as root (it installs and purges the package)"
export DEBIAN_FRONTEND=noninteractive

# --- 1. tools and build dependencies -----------------------------------------------------------
apt-get update -qq || die "apt-get update"
# dpkg-dev, debhelper: the build; lintian; systemd: systemd-analyze; man-db: verify checks the
# unit's Documentation= man pages; mbpoll: the PLC's side; util-linux: setpriv.
apt-get install -y -qq --no-install-recommends build-essential dpkg-dev debhelper lintian \
    systemd man-db mbpoll util-linux procps >/dev/null || die "apt-get install of the tools"
deps="$(mktemp -d)"
cp -a "$here/debian" "$deps/debian"
apt-get build-dep -y -qq "$deps" >/dev/null || die "apt-get build-dep (debian/control)"
rm -rf "$deps"
pass "build dependencies installed"

# --- 2. build and lintian -----------------------------------------------------------------------
# DRIVEGATE_CI_REUSE_DEB=1: take the package packaging/stage/ already holds (to rerun the checks).
if [ "${DRIVEGATE_CI_REUSE_DEB:-0}" != 1 ]; then
    "$here/build-deb.sh" >/tmp/drivegate-build-deb.log 2>&1 ||
        { tail -50 /tmp/drivegate-build-deb.log; die "packaging/build-deb.sh (log above)"; }
fi
version="$(dpkg-parsechangelog -l "$here/debian/changelog" -S Version)"
arch="$(dpkg --print-architecture)"
multiarch="$(dpkg-architecture -qDEB_HOST_MULTIARCH)"
deb="$here/stage/drivegate_${version}_${arch}.deb"
changes="$here/stage/drivegate_${version}_${arch}.changes"
[ -f "$deb" ] || die "no $deb"
pass "package built: $deb"

lintian --fail-on error,warning --display-info --show-overrides "$changes"
check "lintian: no errors, no warnings without an override" test $? -eq 0

# --- 3. install ---------------------------------------------------------------------------------
apt-get install -y -qq "$deb" >/dev/null || die "apt-get install $deb"
pass "apt-get install ./$(basename "$deb")"

plugins="/usr/lib/$multiarch/drivegate/adapters"
unit=/lib/systemd/system/drivegate.service
for f in /usr/sbin/drivegated /usr/bin/drivegate; do check "$f is executable" test -x "$f"; done
# Every adapter of the source tree (a folder with a plugin.cpp), none listed by hand.
for src in "$here"/../adapters/*/plugin.cpp; do
    id="$(basename "$(dirname "$src")")"
    check "plugin $plugins/drivegate-$id.so" test -f "$plugins/drivegate-$id.so"
done
for src in "$here"/../adapters/modbus/profiles/*.toml; do
    check "profile /usr/share/drivegate/profiles/$(basename "$src")" \
        test -f "/usr/share/drivegate/profiles/$(basename "$src")"
done
for src in "$here"/../adapters/framed/protocols/*.toml; do
    check "protocol /usr/share/drivegate/protocols/$(basename "$src")" \
        test -f "/usr/share/drivegate/protocols/$(basename "$src")"
done
check "Grafana dashboard /usr/share/drivegate/grafana/drivegate.json" \
    test -f /usr/share/drivegate/grafana/drivegate.json
check "unit $unit" test -f "$unit"
check "/etc/drivegate/drivegate.toml is a conffile" \
    sh -c "dpkg-query -W -f='\${Conffiles}' drivegate | grep -q '^ /etc/drivegate/drivegate.toml '"
for m in man8/drivegated.8 man1/drivegate.1 man5/drivegate.toml.5; do
    check "man page $m" test -f "/usr/share/man/$m.gz"
done
check "system user drivegate in group dialout" \
    sh -c 'id -nG drivegate | tr " " "\n" | grep -qx dialout'
# shellcheck disable=SC2016 # expanded by the inner sh
check "drivegate has no login shell" \
    sh -c 'case "$(getent passwd drivegate | cut -d: -f7)" in */nologin|*/false) ;; *) exit 1;; esac'
check "Depends carries the shared libraries it links" \
    sh -c "dpkg-query -W -f='\${Depends}' drivegate | grep -q libmodbus5"
check "the service is installed disabled" \
    sh -c '! test -e /etc/systemd/system/multi-user.target.wants/drivegate.service'

# An edit to the conffile survives a reinstall (an upgrade keeps it the same way).
echo "# edited by ci-check" >>/etc/drivegate/drivegate.toml
apt-get install -y -qq --reinstall "$deb" >/dev/null
check "the administrator's edit of drivegate.toml survives a reinstall" \
    grep -qx "# edited by ci-check" /etc/drivegate/drivegate.toml

# --- 4. the unit --------------------------------------------------------------------------------
verify="$(systemd-analyze verify "$unit" 2>&1)"
rc=$?
[ -z "$verify" ] || echo "$verify"
check "systemd-analyze verify: clean" test "$rc" -eq 0 -a -z "$verify"
security="$(systemd-analyze security --offline=yes "$unit" 2>&1)"
exposure="$(echo "$security" | sed -n 's/.*Overall exposure level for drivegate.service: \([0-9.]*\).*/\1/p')"
echo "ci-check: systemd-analyze security --offline=yes: exposure ${exposure:-unknown}"
check "security exposure ${exposure:-unknown} <= 2.0" \
    awk -v e="${exposure:-99}" 'BEGIN { exit !(e <= 2.0) }'

# --- 5. the installed daemon against simulators -------------------------------------------------
run_dir="$(mktemp -d /tmp/drivegate-ci-XXXXXX)"
chown drivegate:drivegate "$run_dir"
# The service's identity without systemd: user drivegate, its groups (dialout), no capability.
# An array, not a function, so that `"${as_drivegate[@]}" prog &` makes $! the program's pid.
as_drivegate=(setpriv --reuid=drivegate --regid=drivegate --init-groups --inh-caps=-all
    --no-new-privs)
sim_pids=()
daemon_pid=""
cleanup() {
    [ -n "$daemon_pid" ] && kill "$daemon_pid" 2>/dev/null
    for p in "${sim_pids[@]}"; do kill "$p" 2>/dev/null; done
    wait 2>/dev/null
    rm -rf "$run_dir"
    [ -z "${stale_lock:-}" ] || rm -f "$stale_lock"
}
trap cleanup EXIT

# What the installed example configuration has, none listed here: on each of its buses'
# /dev/ttyUSB<i> ports (in order), the adapter and address of the device on it, simulated with
# the installed `drivegate sim`; and its devices' unit ids.
example_sims() { # one line per bus, by port: "<adapter> [--address N]"
    awk '
        /^\[/ { section = $0 }
        /^(name|port|bus|adapter|address) *=/ {
            key = $1; value = $0; sub(/^[^=]*= */, "", value); gsub(/"/, "", value)
            if (section == "[[bus]]" && key == "name") bus = value
            if (section == "[[bus]]" && key == "port") port[bus] = value
            if (section == "[[device]]" && key == "bus") dbus = value
            if (section == "[[device]]" && key == "adapter") adapter[dbus] = value
            if (section == "[[device]]" && key == "address") address[dbus] = value
        }
        END {
            for (b in port) {
                n = port[b]; sub(/^\/dev\/ttyUSB/, "", n)
                line[n + 0] = adapter[b] (address[b] != "" ? " --address " address[b] : "")
            }
            for (i = 0; i in line; i++) print line[i]
        }' /etc/drivegate/drivegate.toml
}
mapfile -t sims < <(example_sims)
mapfile -t units < <(sed -n 's/^unit_id = \([0-9]*\)$/\1/p' /etc/drivegate/drivegate.toml)
echo "ci-check: the example's buses: ${sims[*]/%/,} units ${units[*]}"
check "the example configuration names a simulated device on every port" \
    test "${#sims[@]}" -gt 0 -a "${#sims[@]}" -eq "$(grep -c '^port = "/dev/ttyUSB' \
    /etc/drivegate/drivegate.toml)"
for i in "${!sims[@]}"; do
    # shellcheck disable=SC2086 # the adapter and its arguments
    "${as_drivegate[@]}" /usr/bin/drivegate sim ${sims[$i]} --link "$run_dir/ttyUSB$i" \
        </dev/null >"$run_dir/sim$i.out" 2>"$run_dir/sim$i.err" &
    sim_pids+=($!)
done
for i in "${!sims[@]}"; do
    for _ in $(seq 50); do [ -e "$run_dir/ttyUSB$i" ] && break; sleep 0.1; done
    check "simulator ${sims[$i]} on $run_dir/ttyUSB$i" test -e "$run_dir/ttyUSB$i"
done

# A stale port lock of root's, as a root process killed on this machine leaves one (the CI's own
# earlier passes did): the service's user cannot remove it, and its port must open all the same.
# PID 4194303 is the largest Linux hands out and not running here. Only where /run/lock is the
# sticky, world-writable directory Debian makes it (elsewhere the daemon may simply remove it).
stale_lock=""
if [ -d /run/lock ] && [ -k /run/lock ]; then
    stale_lock="/run/lock/LCK..$(readlink -f "$run_dir/ttyUSB1" | sed -e 's|^/dev/||' -e 's|/|_|g')"
    printf '%10d\n' 4194303 >"$stale_lock"
else
    echo "ci-check: /run/lock is not a sticky directory here: the stale-lock check is left out"
fi

config="$run_dir/drivegate.toml"
sed -e "s|\"/dev/ttyUSB\([0-9]\)\"|\"$run_dir/ttyUSB\1\"|" \
    -e "s|^address = \"0.0.0.0:502\"|address = \"127.0.0.1:$port\"|" \
    -e "s|^allow = \[\"192.168.*|allow = [\"127.0.0.1\"]|" /etc/drivegate/drivegate.toml >"$config"
check "the adapted example's PLC listener is on loopback" \
    grep -q "^address = \"127.0.0.1:$port\"" "$config"
chown drivegate:drivegate "$config"
check "the adapted example names the simulators' ports" \
    test "$(grep -c "^port = \"$run_dir/ttyUSB" "$config")" -eq "${#sims[@]}"
check "drivegated --check-config on the adapted example" \
    "${as_drivegate[@]}" /usr/sbin/drivegated --check-config "$config"

"${as_drivegate[@]}" /usr/sbin/drivegated --config "$config" 2>"$run_dir/daemon.log" &
daemon_pid=$!

# Input register 0 of every unit is its status word; bit 0 = online (include/drivegate/common.h).
read_reg() { # read_reg TABLE UNIT REGISTER: prints the value or nothing
    mbpoll -m tcp -p "$port" -a "$2" -t "$1" -0 -r "$3" -c 1 -1 -o 2 127.0.0.1 2>/dev/null |
        sed -n 's/^\[[0-9]*\]:[[:space:]]*\(-\{0,1\}[0-9]*\).*/\1/p'
}
online() { # online UNIT: the unit's status word has bit 0 set
    local s
    s="$(read_reg 3 "$1" 0)"
    [ -n "$s" ] && [ $((s & 1)) -eq 1 ]
}
for unit in "${units[@]}"; do
    for _ in $(seq 60); do online "$unit" && break; sleep 0.5; done
    check "unit $unit online (mbpoll: input register 0 = $(read_reg 3 "$unit" 0))" online "$unit"
done
# Holding register 1 is setpoint_rpm; the ED3100 (unit 2) stores it while stopped.
mbpoll -m tcp -p "$port" -a 2 -t 4 -0 -r 1 -1 -o 5 127.0.0.1 1500 >/dev/null 2>&1
check "unit 2 setpoint_rpm written and read back as 1500" test "$(read_reg 4 2 1)" = 1500

kill -TERM "$daemon_pid"
wait "$daemon_pid"
rc=$?
daemon_pid=""
check "drivegated exits 0 on SIGTERM (got $rc)" test "$rc" -eq 0
for line in "serving ${#units[@]} devices on ${#sims[@]} buses" "signal SIGTERM: shutting down" \
    "stopped" \
    ${stale_lock:+"stale lock $stale_lock of pid 4194303 kept"}; do
    check "the daemon logged '$line'" grep -q "$line" "$run_dir/daemon.log"
done
[ "$failed" -eq 0 ] || { echo "--- daemon log"; cat "$run_dir/daemon.log"; }
cleanup
trap - EXIT

# --- 6. purge -----------------------------------------------------------------------------------
files="$(dpkg-query -L drivegate)"
apt-get purge -y -qq drivegate >/dev/null
check "apt-get purge -y drivegate" test $? -eq 0
status="$(dpkg-query -W -f='${db:Status-Status}' drivegate 2>/dev/null)"
check "dpkg has drivegate as not installed (${status:-unknown})" \
    test -z "$status" -o "$status" = not-installed
left=""
while IFS= read -r f; do
    [ -n "$f" ] || continue
    # Directories other packages share (/usr/lib/<arch>, /etc, ...) stay; drivegate's own go.
    if [ -d "$f" ]; then # a symbolic link to one too (/lib on merged-/usr systems)
        case "$f" in */drivegate | */drivegate/*) [ -e "$f" ] && left+="$f " ;; esac
    elif [ -e "$f" ] || [ -L "$f" ]; then
        left+="$f "
    fi
done <<<"$files"
for f in /etc/drivegate /var/lib/systemd/deb-systemd-helper-enabled/drivegate.service.dsh-also \
    /var/lib/systemd/deb-systemd-helper-masked/drivegate.service \
    /etc/systemd/system/multi-user.target.wants/drivegate.service; do
    { [ -e "$f" ] || [ -L "$f" ]; } && left+="$f "
done
check "nothing left after purge${left:+: $left}" test -z "$left"
# Kept on purpose (as Debian does): the system user and group, which files may still own.
check "the system user drivegate is kept" sh -c "getent passwd drivegate >/dev/null"

finish
