#!/usr/bin/env bash
# make demo: the simulated dark lab end to end. Starts the simulator and every perception and
# mapping process that is built, records the LCM log, writes the mission report and prints
# who was found and how. Runs inside a private network namespace when it can, so the demo's
# multicast stays on this machine.
#
#   launch-scripts/demo.sh [BUILD_DIR]        (env: DEMO_WORLD, DEMO_SECONDS)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
bin="$build/bin"
world="${DEMO_WORLD:-$root/config/worlds/lab_dark.yaml}"
seconds="${DEMO_SECONDS:-90}"

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
stop_all() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for _ in $(seq 50); do
    alive=0; for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break; sleep 0.2
  done
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  pids=()
}
trap stop_all EXIT
start() {  # start NAME ARGS... — in the background, output to $out/NAME.txt
  local name="$1"; shift
  if [ -x "$bin/$name" ]; then
    (cd "$root" && exec "$bin/$name" "$@") >"$out/$name.txt" 2>&1 & pids+=($!)
    started+=("$name")
  else
    missing+=("$name")
  fi
}

echo "== sarmap demo: $(basename "$world"), ${seconds} s simulated; output in $out"
started=(); missing=()
"$bin/sarmap-log-record" -o "$log" --force >"$out/logger.txt" 2>&1 & pids+=($!)
start sarmap-depth --set source=lcm
start sarmap-slam
start sarmap-sound-localisation
start sarmap-speech
start sarmap-vision-people
start sarmap-sound-map
start sarmap-people-map
sleep 2
if [ ! -x "$bin/sarmap-sim" ]; then
  echo "demo: sarmap-sim is not built"; exit 1
fi
echo "   running: ${started[*]}"
[ ${#missing[@]} -eq 0 ] || echo "   not built: ${missing[*]}"
# The simulated robot carries a planar ReSpeaker array (the sound map maps azimuths; the Kinect's
# linear array gives only cone angles), the one config/sound_localisation.yaml and speech.yaml use.
echo "== simulating (the robot follows the world's scripted path)"
(cd "$root" && "$bin/sarmap-sim" --world "$world" --duration "$seconds" --speed 1 --set audio.mic_array=respeaker4) >"$out/sarmap-sim.txt" 2>&1 \
  || echo "   sarmap-sim failed: see $out/sarmap-sim.txt"
sleep 2
stop_all

for name in "${started[@]}"; do
  if grep -qE "^E |terminate|Segmentation|Aborted" "$out/$name.txt" 2>/dev/null; then
    echo "   $name reported errors: see $out/$name.txt"
  fi
done
echo "== the log (sarmap-log info)"
"$bin/sarmap-log" info "$log" || true
echo
echo "== mission report"
"$bin/sarmap-log" report "$log" -o "$out/report"
echo
echo "demo finished: open $out/report/report.html"
