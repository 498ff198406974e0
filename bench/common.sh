# shellcheck shell=bash
# bench/common.sh: what the bench scripts share. Sourced, not run.

# bench_workdir NAME: a fresh working directory in W, and PIDS, whose processes are killed (and
# the directory removed) when the script exits.
bench_workdir() {
  W=$(mktemp -d "/tmp/dg-$1-XXXXXX")
  # The port locks of the benches' daemons and simulators stay in it, never in /run/lock: a
  # killed bench must not leave stale locks a service's user cannot remove.
  export DRIVEGATE_LOCK_DIR="$W"
  PIDS=()
  trap bench_cleanup EXIT
}
bench_cleanup() {
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$W"
}

# wait_for_path PATH: until a simulator has created its pty link (5 s at most).
wait_for_path() {
  for _ in $(seq 50); do [[ -e $1 ]] && return 0; sleep 0.1; done
  return 1
}

# wait_for_port PORT: until something accepts TCP connections on 127.0.0.1:PORT (10 s at most).
wait_for_port() {
  for _ in $(seq 100); do
    (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null && return 0
    sleep 0.1
  done
  echo "${0##*/}: nothing answers on port $1" >&2
  return 1
}

# wait_load: until the 1-minute load average is below LOAD_MAX (LOAD_WAIT s at most, 60 s at a
# time); sets LOAD, with "(!)" appended when it never got there and the run measures anyway.
wait_load() {
  local waited=0
  while true; do
    LOAD=$(cut -d' ' -f1 /proc/loadavg)
    awk -v l="$LOAD" -v m="$LOAD_MAX" 'BEGIN {exit !(l < m)}' && return 0
    if ((waited >= LOAD_WAIT)); then
      echo "${0##*/}: load $LOAD still >= $LOAD_MAX after ${waited}s; measuring anyway" >&2
      LOAD="$LOAD(!)"
      return 0
    fi
    echo "${0##*/}: load $LOAD >= $LOAD_MAX ($(uptime | sed 's/.*average: //')); waiting 60 s" >&2
    sleep 60
    waited=$((waited + 60))
  done
}
