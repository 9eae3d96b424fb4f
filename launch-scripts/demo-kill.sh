#!/usr/bin/env bash
# DEMO_KILL=1 of launch-scripts/demo.sh: once the simulator runs, kill -9 each process of the
# stack once, in turn, evenly over the mission. Only the demo's own processes: children of the
# given deputies (commands run without a shell), never a process of the same name elsewhere on
# the machine.
#
#   launch-scripts/demo-kill.sh DEPUTY_PIDS MISSION_SECONDS [VICTIM...]
#   DEPUTY_PIDS: comma-separated pids of the demo's deputies
set -uo pipefail
[ $# -ge 2 ] || { echo "usage: $0 DEPUTY_PIDS MISSION_SECONDS [VICTIM...]"; exit 2; }
deputies="$1"; seconds="$2"; shift 2
victims=("$@")
[ ${#victims[@]} -gt 0 ] || victims=(sarmap-depth sarmap-slam sarmap-sound-localisation sarmap-speech
                                     sarmap-vision-people sarmap-sound-map sarmap-people-map sarmap-explore)
# (names are longer than pgrep -x sees, hence the pattern on the command line)
running() { pgrep -P "$deputies" -f "(^|/)$1( |\$)" | head -1; }
for _ in $(seq 300); do [ -n "$(running sarmap-sim)" ] && break; sleep 0.2; done
gap=$(( seconds / (${#victims[@]} + 2) ))
[ "$gap" -ge 2 ] || gap=2
for v in "${victims[@]}"; do
  sleep "$gap"
  pid="$(running "$v" || true)"
  if [ -n "$pid" ]; then
    kill -KILL "$pid" && echo "$(date +%T) kill -9 $v (pid $pid)"
  else
    echo "$(date +%T) $v not running"
  fi
done
