#!/usr/bin/env bash
# DEMO_KILL's killer (launch-scripts/demo-kill.sh) kills only the demo's own processes: a
# process of the same name that is not a child of the demo's deputy survives. (It used to
# pgrep the whole machine.)  demo_kill_test.sh SOURCE_DIR
set -uo pipefail
src="$1"
work="$(mktemp -d /tmp/sarmap_demo_kill_XXXXXX)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do pkill -KILL -P "$p" 2>/dev/null; kill -KILL "$p" 2>/dev/null; done
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
for name in sarmap-sim sarmap-depth; do ln -s "$(command -v sleep)" "$work/$name"; done
# A stand-in deputy with the demo's simulator and one victim as its children...
bash -c "'$work/sarmap-sim' 60 & '$work/sarmap-depth' 60 & wait" >/dev/null 2>&1 & deputy=$!
pids+=("$deputy")
# ...and a process of the same name elsewhere on the machine.
"$work/sarmap-depth" 60 >/dev/null 2>&1 & other=$!; pids+=("$other")
for _ in $(seq 50); do [ -n "$(pgrep -P "$deputy" -f sarmap-depth)" ] && break; sleep 0.1; done
ours="$(pgrep -P "$deputy" -f sarmap-depth)"
[ -n "$ours" ] || fail "the stand-in deputy's sarmap-depth did not start"
"$src/launch-scripts/demo-kill.sh" "$deputy" 4 sarmap-depth > "$work/kills.txt" 2>&1 || fail "demo-kill.sh exited with $?"
cat "$work/kills.txt"
grep -q "kill -9 sarmap-depth (pid $ours)" "$work/kills.txt" || fail "the demo's sarmap-depth (pid $ours) was not killed"
kill -0 "$other" 2>/dev/null || fail "a sarmap-depth outside the demo (pid $other) was killed"
echo "PASS: killed the demo's sarmap-depth (pid $ours); the one outside the demo (pid $other) lives"
