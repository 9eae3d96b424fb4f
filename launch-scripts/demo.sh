#!/usr/bin/env bash
# make demo: a simulated mission end to end under the launcher. Starts a procman deputy, has
# the sheriff run the "mission" script of launch-scripts/demo.pmd (recorder, mapping,
# perception, then the simulator; everything stopped when the simulator ends), then writes
# the mission report and the stack's CPU and latency figures, and prints who was found and how.
# Runs inside a private network namespace when it can, so the demo's multicast stays here.
# The operator's live page (sarmap-viewer) runs with the mission; its address is printed at
# start: the namespace's 127.0.0.1 is not this computer's, so launch-scripts/viewer_forward.py
# forwards a port of this computer's 127.0.0.1 into it (through a Unix socket, a file both see).
#
#   launch-scripts/demo.sh [BUILD_DIR]
#   env: DEMO_WORLD   world file (default config/worlds/lab_dark.yaml)
#        DEMO_SITE=N  a generated incident site instead (sarmap-site --seed N; default 600 s)
#        DEMO_SECONDS simulated seconds (default 90)
#        DEMO_DRIVE   explore (default: the robot searches on its own) or path (the world's
#                     scripted path)
#        DEMO_EXPLORE_MODE  sound_guided (default), frontier or reactive
#        DEMO_WHEN_EXPLORED  home (default: the robot comes back and waits) or sweep (it
#                     searches the explored site again until the mission ends: long missions)
#        DEMO_RECORD_PROFILE  a recording profile for sarmap-log record (e.g.
#                     config/record_long.yaml: camera frames thinned, for missions of hours)
#        DEMO_KILL=1  kill -9 each process of the stack once, in turn, mid-mission: the launcher
#                     respawns it and the report must not lose anyone
#        DEMO_OUT     output folder (default out/demo-DATE)
#        DEMO_VIEWER_PORT  port of the live page on this computer's 127.0.0.1 (default 8080, a
#                     free one when taken); its address is printed at start
#        DEMO_COMPUTERS=2  two computers: deputies "sensors" and "compute" in two network
#                     namespaces joined by a bridge, LCM at ttl=1 between them, the sheriff in a
#                     third (launch-scripts/demo-two-computers.pmd); needs root or user namespaces
#        DEMO_HOSTILE=1  an attacked mission (make demo-hostile): once the simulator has run for
#                     DEMO_HOSTILE_DELAY s (default 5), sarmap-net-fuzz sends crafted datagrams to
#                     every channel of the demo's bus (DEMO_HOSTILE_RATE per second, default
#                     500, DEMO_HOSTILE_SEED its random choices, default 1) until 5 s before
#                     the simulator stops, and DEMO_LOSS_PERCENT
#                     (default 10) of the datagrams are lost; only inside the demo's private
#                     network namespace
#        DEMO_LOSS_PERCENT=N  datagram loss on the demo's bus, N % (iptables' statistic match on
#                     every multicast datagram received in the demo's namespace: every receiver
#                     loses the same ones; with two computers each loses its own); needs the
#                     private network namespace and iptables
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
bin="$build/bin"
if [ -n "${DEMO_SITE:-}" ]; then
  export DEMO_SECONDS="${DEMO_SECONDS:-600}"
else
  export DEMO_WORLD="${DEMO_WORLD:-$root/config/worlds/lab_dark.yaml}"
  export DEMO_SECONDS="${DEMO_SECONDS:-90}"
fi
case "${DEMO_DRIVE:-explore}" in
  explore) export DEMO_SIM_DRIVE=cmd_vel ;;
  path) export DEMO_SIM_DRIVE=path ;;
  *) echo "demo: DEMO_DRIVE must be explore or path"; exit 2 ;;
esac
export DEMO_EXPLORE_MODE="${DEMO_EXPLORE_MODE:-sound_guided}"

if [ -z "${SARMAP_NETNS:-}" ] && [ -z "${SARMAP_DEMO_NO_NETNS:-}" ]; then
  if "$root/tests/harness/sarmap-netns" true 2>/dev/null; then
    # The live page's forwarder on this side; it exits with this process (whose pid the execs
    # keep).
    viewer_dir="$(mktemp -d /tmp/sarmap-demo-viewer.XXXXXX)"
    python3 "$root/launch-scripts/viewer_forward.py" host --port "${DEMO_VIEWER_PORT:-8080}" \
      --socket "$viewer_dir/viewer.sock" --port-file "$viewer_dir/port" --parent $$ >/dev/null 2>&1 &
    for _ in $(seq 50); do [ -s "$viewer_dir/port" ] && break; sleep 0.1; done
    if [ -s "$viewer_dir/port" ]; then
      export DEMO_VIEWER_URL="http://127.0.0.1:$(cat "$viewer_dir/port")/"
      export DEMO_VIEWER_SOCKET="$viewer_dir/viewer.sock"
    fi
    exec "$root/tests/harness/sarmap-netns" "$0" "$build"
  fi
  echo "demo: no private network namespace available; using host-local multicast (ttl=0)"
fi

computers="${DEMO_COMPUTERS:-1}"
case "$computers" in 1|2) ;; *) echo "demo: DEMO_COMPUTERS must be 1 or 2"; exit 2 ;; esac
hostile="${DEMO_HOSTILE:-}"
case "$hostile" in ""|0|1) ;; *) echo "demo: DEMO_HOSTILE must be 1 (or empty)"; exit 2 ;; esac
[ "$hostile" = 1 ] || hostile=""
loss_percent="${DEMO_LOSS_PERCENT:-${hostile:+10}}"
loss_percent="${loss_percent:-0}"
[[ "$loss_percent" =~ ^[0-9]+([.][0-9]+)?$ ]] && awk -v p="$loss_percent" 'BEGIN { exit !(p < 100) }' \
  || { echo "demo: DEMO_LOSS_PERCENT must be a number from 0 to below 100"; exit 2; }
if [ -n "$hostile" ] || [ "$loss_percent" != 0 ]; then
  # An attack on the bus and lost datagrams stay inside the demo's own network namespace.
  [ -n "${SARMAP_NETNS:-}" ] || { echo "demo: DEMO_HOSTILE and DEMO_LOSS_PERCENT need a private network namespace (root or user namespaces)"; exit 1; }
fi
if [ "$computers" = 2 ] && [ -z "${DEMO_MOUNT_NS:-}" ]; then
  [ -n "${SARMAP_NETNS:-}" ] || { echo "demo: two computers need a private network namespace (root or user namespaces)"; exit 1; }
  # A private mount namespace for /run/netns, so the demo's namespaces never meet anyone else's.
  export DEMO_MOUNT_NS=1
  exec unshare --mount --propagation private -- "$0" "$build"
fi

programs="sarmap-sim sarmap-procman sarmap-procman-deputy sarmap-log-record sarmap-log-report"
[ -z "$hostile" ] || programs="$programs sarmap-net-fuzz"
for program in $programs; do
  [ -x "$bin/$program" ] || { echo "demo: $bin/$program is not built (run make build)"; exit 1; }
done
export DEMO_OUT="${DEMO_OUT:-$root/out/demo-$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$DEMO_OUT"
out="$DEMO_OUT"
if [ -n "${DEMO_SITE:-}" ]; then
  [ -x "$bin/sarmap-site" ] || { echo "demo: $bin/sarmap-site is not built (run make build)"; exit 1; }
  export DEMO_WORLD="$out/site-$DEMO_SITE.yaml"
  (cd "$root" && "$bin/sarmap-site" --seed "$DEMO_SITE" -o "$DEMO_WORLD") | sed 's/^/   /'
fi
case "$DEMO_WORLD" in /*) ;; *) DEMO_WORLD="$root/$DEMO_WORLD" ;; esac
[ -f "$DEMO_WORLD" ] || { echo "demo: no world file $DEMO_WORLD"; exit 1; }
log="$out/demo.lcmlog"

# The launcher obeys only signed orders: a key for this demo only. The bus is signed too
# (common/bus_auth.h): every node and deputy signs what it publishes with a second key and acts
# only on messages signed with it, so nothing another host publishes reaches the stack.
export DEMO_PROCMAN_KEY="$out/procman.key"
(umask 077 && head -c 32 /dev/urandom >"$DEMO_PROCMAN_KEY")
export DEMO_BUS_KEY="$out/bus.key"
(umask 077 && head -c 32 /dev/urandom >"$DEMO_BUS_KEY")

pids=()
stop_all() {
  [ -z "${DEMO_VIEWER_SOCKET:-}" ] || rm -rf "$(dirname "$DEMO_VIEWER_SOCKET")"
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for _ in $(seq 100); do
    alive=0; for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break; sleep 0.2
  done
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  pids=()
}
trap stop_all EXIT

echo "== sarmap demo: $(basename "$DEMO_WORLD"), ${DEMO_SECONDS} s simulated, driven by ${DEMO_DRIVE:-explore} ($DEMO_EXPLORE_MODE), $computers computer(s); output in $out"
pmd="$root/launch-scripts/demo.pmd"
if [ "$computers" = 1 ]; then
  # The live page (sarmap-viewer in demo.pmd, bound to 127.0.0.1).
  if [ -n "${SARMAP_NETNS:-}" ]; then
    export DEMO_VIEWER_BIND_PORT=8080  # the namespace's own port space
    if [ -n "${DEMO_VIEWER_SOCKET:-}" ]; then
      python3 "$root/launch-scripts/viewer_forward.py" inside --socket "$DEMO_VIEWER_SOCKET" \
        --to-port "$DEMO_VIEWER_BIND_PORT" --parent $$ >"$out/viewer_forward.txt" 2>&1 & pids+=($!)
      viewer_url="$DEMO_VIEWER_URL"
    else
      viewer_url="http://127.0.0.1:$DEMO_VIEWER_BIND_PORT/ (inside the network namespace the demo runs in)"
    fi
  else
    DEMO_VIEWER_BIND_PORT="$(python3 -c 'import socket,sys
s = socket.socket()
try: s.bind(("127.0.0.1", int(sys.argv[1])))
except OSError: s.bind(("127.0.0.1", 0))
print(s.getsockname()[1])' "${DEMO_VIEWER_PORT:-8080}")"
    export DEMO_VIEWER_BIND_PORT
    viewer_url="http://127.0.0.1:$DEMO_VIEWER_BIND_PORT/"
  fi
  echo "== live page while the mission runs: $viewer_url"
  (cd "$root" && exec "$bin/sarmap-procman-deputy" --id localhost --key "$DEMO_PROCMAN_KEY" --bus-key-file "$DEMO_BUS_KEY") \
    >"$out/deputy.txt" 2>&1 & pids+=($!)
else
  pmd="$root/launch-scripts/demo-two-computers.pmd"
  namespaces=()
  # shellcheck source=../tests/harness/netns-hosts.sh
  source "$root/tests/harness/netns-hosts.sh"
  cleanup_netns() { stop_all; netns_remove_hosts "${namespaces[@]}"; }
  trap cleanup_netns EXIT
  # The robot's network: a bridge here (where the sheriff runs), one veth pair per computer.
  netns_bridge_up || { echo "demo: cannot create network namespaces and a bridge here"; exit 1; }
  export SARMAP_LCM_URL="udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608"
  i=2
  for id in sensors compute; do
    ns="demo-$id"
    netns_add_host "$ns" "$i"; namespaces+=("$ns")
    [ "$id" != compute ] || export DEMO_VIEWER_BIND_ADDRESS="10.77.0.$i"
    (cd "$root" && exec ip netns exec "$ns" "$bin/sarmap-procman-deputy" --id "$id" --key "$DEMO_PROCMAN_KEY" --bus-key-file "$DEMO_BUS_KEY") \
      >"$out/deputy-$id.txt" 2>&1 & pids+=($!)
    echo "   computer '$id': network namespace $ns, 10.77.0.$i"
    i=$((i + 1))
  done
  # The live page runs on "compute", bound to its address on the robot's network (reachable
  # from here, where the bridge is); forwarded to this computer's 127.0.0.1.
  if [ -n "${DEMO_VIEWER_SOCKET:-}" ]; then
    python3 "$root/launch-scripts/viewer_forward.py" inside --socket "$DEMO_VIEWER_SOCKET" \
      --to-host "$DEMO_VIEWER_BIND_ADDRESS" --to-port 8080 --parent $$ >"$out/viewer_forward.txt" 2>&1 & pids+=($!)
    echo "== live page while the mission runs: $DEMO_VIEWER_URL (sarmap-viewer on 'compute', $DEMO_VIEWER_BIND_ADDRESS:8080)"
  else
    echo "== live page while the mission runs: http://$DEMO_VIEWER_BIND_ADDRESS:8080/ (inside the network namespace the demo runs in)"
  fi
fi

# Datagram loss: a statistic match drops that share of the multicast datagrams each namespace
# receives (in the demo's namespace, or each computer's); counted by a rule before it.
loss_namespaces=()
loss_rule() {  # NAMESPACE (empty: this one) ARGS...
  local ns="$1"; shift
  if [ -n "$ns" ]; then ip netns exec "$ns" iptables "$@"; else iptables "$@"; fi
}
if [ "$loss_percent" != 0 ]; then
  command -v iptables >/dev/null || { echo "demo: DEMO_LOSS_PERCENT needs iptables (apt-get install iptables)"; exit 1; }
  if [ "$computers" = 1 ]; then loss_namespaces=(""); else loss_namespaces=("${namespaces[@]}"); fi
  probability="$(awk -v p="$loss_percent" 'BEGIN { printf "%.4f", p / 100 }')"
  for ns in "${loss_namespaces[@]}"; do
    loss_rule "$ns" -A INPUT -p udp -d 224.0.0.0/4 -m comment --comment sarmap-demo-received \
      || { echo "demo: cannot set the loss rule with iptables"; exit 1; }
    loss_rule "$ns" -A INPUT -p udp -d 224.0.0.0/4 -m statistic --mode random --probability "$probability" \
      -m comment --comment sarmap-demo-loss -j DROP || { echo "demo: cannot set the loss rule with iptables"; exit 1; }
  done
  echo "== $loss_percent % of the bus's datagrams are lost (iptables statistic match, each computer its own)"
fi
loss_report() {
  local ns received dropped
  for ns in "${loss_namespaces[@]}"; do
    received="$(loss_rule "$ns" -L INPUT -v -n -x | awk '/sarmap-demo-received/ { print $1 }')"
    dropped="$(loss_rule "$ns" -L INPUT -v -n -x | awk '/sarmap-demo-loss/ { print $1 }')"
    echo "   datagrams lost${ns:+ on $ns}: $dropped of $received received ($(awk -v d="$dropped" -v r="$received" 'BEGIN { printf "%.1f", (r > 0) ? 100 * d / r : 0 }') %)"
  done
}

# The attacker: once the simulator runs (and every node has its own clocks), a hostile publisher
# on every channel until shortly before the simulator stops, so the final maps are the nodes'.
attacker_pid=""
if [ -n "$hostile" ]; then
  delay_s="${DEMO_HOSTILE_DELAY:-5}"
  rate="${DEMO_HOSTILE_RATE:-500}"
  fuzz_s="$(awk -v t="$DEMO_SECONDS" -v d="$delay_s" 'BEGIN { s = t - d - 5; printf "%.0f", s < 5 ? 5 : s }')"
  echo "== hostile publisher: sarmap-net-fuzz, $rate datagrams/s to every channel for $fuzz_s s, from $delay_s s after the simulator starts"
  (
    deputies="$(IFS=,; echo "${pids[*]}")"
    for _ in $(seq 600); do pgrep -P "$deputies" -f "(^|/)sarmap-sim( |\$)" >/dev/null && break; sleep 0.2; done
    sleep "$delay_s"
    exec "$bin/sarmap-net-fuzz" --seconds "$fuzz_s" --rate "$rate" --seed "${DEMO_HOSTILE_SEED:-1}"
  ) >"$out/net-fuzz.txt" 2>&1 &
  attacker_pid=$!
fi

killer_pid=""
if [ "${DEMO_KILL:-}" = 1 ]; then
  # Once the simulator runs, kill -9 each process of the stack in turn, evenly over the mission;
  # only children of this demo's deputies.
  "$root/launch-scripts/demo-kill.sh" "$(IFS=,; echo "${pids[*]}")" "$DEMO_SECONDS" \
    >"$out/kills.txt" 2>&1 &
  killer_pid=$!
fi

echo "== the launcher runs the mission ($(basename "$pmd"), script \"mission\")"
if ! (cd "$root" && "$bin/sarmap-procman" --key "$DEMO_PROCMAN_KEY" --bus-key-file "$DEMO_BUS_KEY" "$pmd" run mission) >"$out/sheriff.txt" 2>&1; then
  echo "   the mission script failed: see $out/sheriff.txt"
  tail -5 "$out/sheriff.txt" | sed 's/^/   /'
fi
[ -z "$killer_pid" ] || { wait "$killer_pid" 2>/dev/null || true; sed 's/^/   /' "$out/kills.txt"; }
if [ -n "$attacker_pid" ]; then
  kill -TERM "$attacker_pid" 2>/dev/null || true  # (a background job ignores SIGINT)
  wait "$attacker_pid" 2>/dev/null || true
  echo "== the attack"
  sed 's/^/   /' "$out/net-fuzz.txt"
fi
[ "$loss_percent" = 0 ] || loss_report
stop_all
# What each process printed (recorded from the launcher's PM_OUTPUT) into $out/output/.
mkdir -p "$out/output"
"$bin/sarmap-log" output "$log" -o "$out/output" --key "$DEMO_PROCMAN_KEY" 2>/dev/null || true
for f in "$out"/output/*.txt; do
  [ -f "$f" ] || continue
  if grep -qE "^E |terminate called|Segmentation|Aborted|exited with code [1-9]" "$f"; then
    echo "   $(basename "$f" .txt) reported errors: see $f"
  fi
done

echo "== the log (sarmap-log info)"
"$bin/sarmap-log" info "$log" || true
echo
echo "== what the stack cost (sarmap-log perf)"
"$bin/sarmap-log" perf "$log" --key "$DEMO_PROCMAN_KEY" --bus-key-file "$DEMO_BUS_KEY" | tee "$out/perf.txt" || true
echo
echo "== mission report"
"$bin/sarmap-log" report "$log" -o "$out/report" --bus-key-file "$DEMO_BUS_KEY"
echo
echo "demo finished: open $out/report/report.html (map.tif: the GeoTIFF; the live page stopped with the mission)"
