#!/usr/bin/env bash
# Two computers: deputies "sensors" and "compute" in two network namespaces, joined by veth
# pairs to a bridge in a third namespace that runs the sheriff. Runs the layout of
# launch-scripts/robot-two-computers.pmd (every exec replaced by a marked `sleep`, since the
# drivers need hardware) from a one-shot sheriff while a live sheriff keeps sending the desired
# state, cuts the sensors link and checks that the live sheriff shows that deputy as LOST,
# then back when the link returns, and that its processes kept running throughout.
#
# Run by CTest inside tests/harness/sarmap-netns (the third namespace is that one). Needs
# root or unprivileged user namespaces. Namespace names carry our PID, and /run/netns is a
# private tmpfs in a private mount namespace, so parallel runs never collide; a trap always
# cleans up.
set -euo pipefail

if [ "${PROCMAN_TWO_INNER:-}" != 1 ]; then
  export PROCMAN_TWO_INNER=1
  exec unshare --mount --propagation private -- "$0" "$@"
fi

BIN="${SARMAP_BIN_DIR:?SARMAP_BIN_DIR not set}"
SRC="${SARMAP_SOURCE_DIR:?SARMAP_SOURCE_DIR not set}"
source "$SRC/tests/harness/netns-hosts.sh"
TAG="pm$$"
NS_SENSORS="${TAG}-sensors"
NS_COMPUTE="${TAG}-compute"
MARK="7$(printf '%05d' $(( $$ % 100000 )))"   # sleep length marking our processes
URL="udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608"
WORK="$(mktemp -d /tmp/procman_two_XXXXXX)"
PIDS=()

log() { printf '%s %s\n' "$(date +%H:%M:%S.%N | cut -c1-12)" "$*"; }
fail() { log "FAIL: $*"; exit 1; }

cleanup() {
  set +e
  for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null; done
  for _ in $(seq 50); do
    alive=0
    for p in "${PIDS[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  netns_remove_hosts "$NS_SENSORS" "$NS_COMPUTE"
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
  if [ "${KEEP_LOGS:-}" != 1 ]; then rm -rf "$WORK"; else log "logs kept in $WORK"; fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# --- the network: br0 here, one veth pair per computer --------------------------------------
if ! netns_bridge_up 2>/dev/null; then
  echo "SKIP: cannot create network namespaces and a bridge here (needs root, or user namespaces with /run/netns)"
  exit 77
fi
i=2
for ns in "$NS_SENSORS" "$NS_COMPUTE"; do
  netns_add_host "$ns" "$i"
  i=$((i + 1))
done
SENSORS_PORT=vp2

# --- key, config ------------------------------------------------------------------------------
head -c 32 /dev/urandom > "$WORK/procman.key"
chmod 600 "$WORK/procman.key"
sed -E "s/exec = \"[^\"]*\"/exec = \"sleep $MARK\"/" "$SRC/launch-scripts/robot-two-computers.pmd" > "$WORK/two.pmd"
export SARMAP_LCM_URL="$URL"

# --- deputies on the two computers, a live sheriff on the third -----------------------------
for id in sensors compute; do
  ns="${TAG}-$id"
  ip netns exec "$ns" env SARMAP_LCM_URL="$URL" "$BIN/sarmap-procman-deputy" --id "$id" \
    --key "$WORK/procman.key" > "$WORK/deputy-$id.log" 2>&1 &
  PIDS+=($!)
done
# A live sheriff (sends the desired state every second) whose event log we read.
"$BIN/sarmap-procman" "$WORK/two.pmd" --key "$WORK/procman.key" --sheriff-id live-sheriff \
  > "$WORK/observer.log" 2>&1 < /dev/null &
PIDS+=($!)

wait_for() {  # wait_for SECONDS COMMAND...
  local limit=$1; shift
  local end=$(( $(date +%s%N) + limit * 1000000000 ))
  until "$@"; do
    [ "$(date +%s%N)" -lt $end ] || return 1
    sleep 0.05
  done
}
observed() { grep -q "$1" "$WORK/observer.log"; }

wait_for 10 observed "deputy 'sensors' seen" || fail "sensors deputy never seen: $(cat "$WORK/observer.log")"
wait_for 10 observed "deputy 'compute' seen" || fail "compute deputy never seen"
log "both deputies seen across the bridge"

# --- start the two-computer system from the sheriff namespace ---------------------------------
"$BIN/sarmap-procman" "$WORK/two.pmd" --key "$WORK/procman.key" run start || fail "run start failed"
count_marked() {  # count_marked NAMESPACE
  local n=0
  for p in $(ip netns pids "$1"); do
    [ "$(tr '\0' ' ' < /proc/$p/cmdline 2>/dev/null)" = "sleep $MARK " ] && n=$((n + 1))
  done
  echo $n
}
marked_pids() {
  for p in $(ip netns pids "$1"); do
    [ "$(tr '\0' ' ' < /proc/$p/cmdline 2>/dev/null)" = "sleep $MARK " ] && echo "$p"
  done | sort -n | tr '\n' ' '
}
n_sensors=$(grep -c 'deputy = "sensors"' "$WORK/two.pmd")
n_compute=$(grep -c 'deputy = "compute"' "$WORK/two.pmd")
# The script starts everything but the explorer (started by hand): compute runs one fewer.
wait_for 10 test "$(count_marked "$NS_SENSORS")" = "$n_sensors" || fail "sensors runs $(count_marked "$NS_SENSORS")/$n_sensors"
wait_for 10 test "$(count_marked "$NS_COMPUTE")" = "$((n_compute - 1))" || fail "compute runs $(count_marked "$NS_COMPUTE")"
SENSOR_PIDS_BEFORE="$(marked_pids "$NS_SENSORS")"
log "running: sensors [$SENSOR_PIDS_BEFORE], compute $(count_marked "$NS_COMPUTE") processes"

# --- cut the sensors link ----------------------------------------------------------------------
sleep 1.5
t_cut=$(date +%s.%N)
ip link set "$SENSORS_PORT" down
log "cut the link to 'sensors'"
wait_for 10 observed "deputy 'sensors' LOST" || fail "sensors never shown as lost"
t_lost=$(grep -m1 "deputy 'sensors' LOST" "$WORK/observer.log" | sed -E 's/^\[([0-9.]+)\].*/\1/')
awk -v a="$t_cut" -v b="$t_lost" 'BEGIN { printf "FIGURE link cut -> deputy shown LOST: %.3f s (acceptance: within 3 s)\n", b - a }'
sleep 2
observed "deputy 'compute' LOST" && fail "compute was shown lost but its link was not cut"
[ "$(marked_pids "$NS_SENSORS")" = "$SENSOR_PIDS_BEFORE" ] || fail "sensors processes changed while cut off"

# --- restore it ----------------------------------------------------------------------------------
t_up=$(date +%s.%N)
ip link set "$SENSORS_PORT" up
log "restored the link"
wait_for 10 observed "deputy 'sensors' back" || fail "sensors never shown back"
t_back=$(grep -m1 "deputy 'sensors' back" "$WORK/observer.log" | sed -E 's/^\[([0-9.]+)\].*/\1/')
awk -v a="$t_up" -v b="$t_back" 'BEGIN { printf "FIGURE link restored -> deputy shown again: %.3f s\n", b - a }'
sleep 1.5
[ "$(marked_pids "$NS_SENSORS")" = "$SENSOR_PIDS_BEFORE" ] || fail "sensors processes changed: [$SENSOR_PIDS_BEFORE] -> [$(marked_pids "$NS_SENSORS")]"
grep -q "REFUSED" "$WORK/deputy-sensors.log" && fail "sensors refused orders: $(grep REFUSED "$WORK/deputy-sensors.log")"
log "sensors processes kept running: [$SENSOR_PIDS_BEFORE]"
"$BIN/sarmap-procman" "$WORK/two.pmd" status

# --- and stop everything from the sheriff -------------------------------------------------------
"$BIN/sarmap-procman" "$WORK/two.pmd" --key "$WORK/procman.key" run stop > "$WORK/stop.log" 2>&1 || fail "run stop failed: $(cat "$WORK/stop.log")"
wait_for 10 test "$(count_marked "$NS_SENSORS")$(count_marked "$NS_COMPUTE")" = "00" || fail "processes left after stop"
log "PASS"
