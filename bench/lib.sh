# shellcheck shell=bash disable=SC2034 # DRIVES, SIM_IN and START are for the scripts that source this
# bench/lib.sh: the gateway under test that bench/run.sh and bench/tls.sh share. Sourced, after
# bench/common.sh (it uses W, PIDS and wait_for_path), not run. Needs LOAD_CPU and SERVER_CPU.

# adapter unit options
DRIVES=(
  "nidec-washer 1 platform=7"
  "ed3100 2 -"
  "mdriver-2400 3 -"
  "fdc1 4 slave_mode=true"
  "unicla-edrive 5 -"
)
declare -A SIM_IN

# start_gateway BIN_DIR TAG SERVER_TOML: five simulated drives (on $LOAD_CPU) and a drivegated of
# BIN_DIR polling them (on $SERVER_CPU); its configuration starts with SERVER_TOML (the [server]
# table and any [[listener]] tables). Sets GATEWAY_PID. The simulators' stdin fifos are kept in
# SIM_IN under "TAG/adapter".
start_gateway() {
  local bin=$1 tag=$2 dir=$W/$2
  mkdir -p "$dir"
  printf '%s\n' "$3" >"$dir/bench.toml"
  local d id unit opt fd set_arg
  for d in "${DRIVES[@]}"; do
    read -r id unit opt <<<"$d"
    mkfifo "$dir/$id.in"
    exec {fd}<>"$dir/$id.in"
    SIM_IN[$tag/$id]=$fd
    set_arg=()
    [[ $opt != - ]] && set_arg=(--set "$opt")
    taskset -c "$LOAD_CPU" "$bin/drivegate" sim "$id" --plugin-dir "$bin/../adapters" \
      --link "$dir/$id" "${set_arg[@]}" <"$dir/$id.in" >"$dir/$id.out" 2>&1 &
    PIDS+=($!)
    {
      echo; echo "[[bus]]"; echo "name = \"$id\""; echo "port = \"$dir/$id\""
      echo; echo "[[device]]"; echo "name = \"$id\""; echo "bus = \"$id\""
      echo "adapter = \"$id\""; echo "unit_id = $unit"
      if [[ $opt != - ]]; then echo "[device.options]"; echo "${opt%%=*} = ${opt#*=}"; fi
      # 125 ed3100 parameters: holding registers 16..140, the FC03 of 125 the issue asks for.
      if [[ $id == ed3100 ]]; then
        echo "[device.options]"
        printf 'parameters = ['
        for i in $(seq 0 124); do
          printf '%s"%02d-%02d"' "$([[ $i -gt 0 ]] && echo ,)" $((i / 100)) $((i % 100))
        done
        echo ']'
      fi
    } >>"$dir/bench.toml"
  done
  for d in "${DRIVES[@]}"; do
    read -r id _ <<<"$d"
    wait_for_path "$dir/$id" || true
  done
  taskset -c "$SERVER_CPU" "$bin/drivegated" --config "$dir/bench.toml" \
    --plugin-dir "$bin/../adapters" --log-level warn >"$dir/drivegated.log" 2>&1 &
  GATEWAY_PID=$!
  PIDS+=("$GATEWAY_PID")
}

# Start every drive (command = run_forward, setpoint) so the polls carry live values: FC16 through
# a listener that may write.
# shellcheck disable=SC2054 # the commas are in the values (UNIT:ADDR=V1,V2)
START=(1:0=1,800 2:0=1,1500 3:0=1,1149 4:0=1,2000 5:0=1,3000)
