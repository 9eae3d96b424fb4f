#!/usr/bin/env bash
# make demo: runs what exists of the stack end to end, records the LCM log, reports on it,
# and says what is still missing. Runs inside a private network namespace when it can, so
# the demo's multicast stays on this machine.
#
#   launch-scripts/demo.sh [BUILD_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
bin="$build/bin"

if [ -z "${SARMAP_NETNS:-}" ] && [ -z "${SARMAP_DEMO_NO_NETNS:-}" ]; then
  if "$root/tests/harness/sarmap-netns" true 2>/dev/null; then
    exec "$root/tests/harness/sarmap-netns" "$0" "$build"
  fi
  echo "demo: no private network namespace available; using host-local multicast (ttl=0)"
fi

out="$root/out/demo-$(date +%Y%m%d-%H%M%S)"
mkdir -p "$out"
log="$out/demo.lcmlog"
pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT

echo "== sarmap demo: output in $out"
stack=(sarmap-sim sarmap-depth sarmap-audio-capture sarmap-sound-localisation sarmap-speech
       sarmap-vision-people sarmap-slam sarmap-sound-map sarmap-people-map sarmap-explore
       sarmap-viewer sarmap-procman sarmap-procman-deputy)
present=(); missing=()
for p in "${stack[@]}"; do
  if [ -x "$bin/$p" ]; then present+=("$p"); else missing+=("$p"); fi
done
echo "   built:   ${present[*]:-none of the stack yet} (plus sarmap-monitor, sarmap-log)"
echo "   missing: ${missing[*]:-nothing}"

"$bin/sarmap-log-record" -o "$log" --force >"$out/logger.txt" 2>&1 & pids+=($!)
"$bin/sarmap-monitor" --set print_period_s=2 >"$out/monitor.txt" 2>&1 & pids+=($!)
sleep 0.5

if [ -x "$bin/sarmap-sim" ]; then
  echo "== running the simulator"
  "$bin/sarmap-sim" --duration 10 >"$out/sim.txt" 2>&1 || echo "   sarmap-sim failed: see $out/sim.txt"
else
  echo "== no simulator yet: streaming 5 s of synthetic 640x480 depth + colour at 30 Hz instead"
  "$bin/sarmap-test-peer" stream --seconds 5 --rate 30 >"$out/stream.txt" 2>&1
fi
sleep 1
cleanup
pids=()

echo "== what the log holds (sarmap-log info)"
"$bin/sarmap-log" info "$log"
echo
echo "== last monitor table"
awk '/^channel/{block=""} /^channel/,/^$/{block=block $0 "\n"} END{printf "%s", block}' "$out/monitor.txt"
echo
echo "demo finished. Log: $log"
if [ ${#missing[@]} -gt 0 ]; then
  echo "Still missing from the full mission (see the open issues): ${missing[*]}"
fi
