#!/usr/bin/env bash
# make demo, shortened: the dark-lab mission under the launcher (deputy + sheriff running
# launch-scripts/demo.pmd's "mission" script), recorded, with the stack's CPU and the report.
# Checks that every process of the stack ran to the end without a restart, that the people map
# was published and recorded, that the report was written and puts someone on the map, and
# that the launcher's figures (CPU per process) are in the log; and that replaying the log through
# sarmap-people-map twice gives the same people map.
# Run by CTest inside tests/harness/sarmap-netns.
set -euo pipefail
BIN="${SARMAP_BIN_DIR:?SARMAP_BIN_DIR not set}"
SRC="${SARMAP_SOURCE_DIR:?SARMAP_SOURCE_DIR not set}"
out="$(mktemp -d /tmp/sarmap_demo_test_XXXXXX)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; echo "--- demo output"; cat "$out/demo.txt" || true; exit 1; }
source "$SRC/tests/harness/demo_checks.sh"

DEMO_SECONDS="${DEMO_TEST_SECONDS:-20}" DEMO_OUT="$out/run" "$SRC/launch-scripts/demo.sh" "$BIN/.." \
  >"$out/demo.txt" 2>&1 || fail "demo.sh exited with $?"
grep -q "the mission script failed" "$out/demo.txt" && fail "the launcher's mission script failed: $(cat "$out/run/sheriff.txt")"
[ -s "$out/run/demo.lcmlog" ] || fail "no log recorded"
[ -s "$out/run/report/report.html" ] && [ -s "$out/run/report/map.png" ] && [ -s "$out/run/report/report.json" ] \
  || fail "the report is incomplete"
check_ran_without_restart "$out/run/perf.txt" "" sarmap-depth sarmap-slam sarmap-sound-localisation \
  sarmap-speech sarmap-vision-people sarmap-sound-map sarmap-people-map sarmap-explore
grep -q "^stack CPU:" "$out/run/perf.txt" || fail "no stack CPU figure"
grep -Eq "latency DEPTH -> PEOPLE_VISUAL: [0-9]+ frames" "$out/run/perf.txt" || fail "no DEPTH -> PEOPLE_VISUAL latency"
people="$(sed -nE 's/^mission: .*; ([0-9]+) people on the map.*/\1/p' "$out/demo.txt")"
[ -n "$people" ] && [ "$people" -ge 1 ] || fail "nobody on the map after the mission"
grep -E "^mission:|FOUND|MISSED|^stack CPU|latency" "$out/demo.txt"

# Replaying the demo's log through sarmap-people-map gives the same people map every time.
for run in 1 2; do
  "$BIN/sarmap-people-map" --set "state_file=$out/replay$run.yaml" --set save_period_s=0.2 \
    >"$out/people_map_replay$run.txt" 2>&1 &
  pm=$!
  # The replay starts once the node has subscribed (it logs "running" when its loop starts): a
  # replay begun earlier loses its first seconds of detections.
  for _ in $(seq 100); do
    grep -q "running (pid" "$out/people_map_replay$run.txt" && break
    sleep 0.1
  done
  grep -q "running (pid" "$out/people_map_replay$run.txt" \
    || fail "sarmap-people-map did not start for replay $run: $(cat "$out/people_map_replay$run.txt")"
  "$BIN/sarmap-log" replay "$out/run/demo.lcmlog" --speed 4 --channels '^(POSE|PEOPLE_VISUAL|PEOPLE_AUDIO|SOUND_MAP)$' \
    >/dev/null 2>&1 || fail "replay $run failed"
  sleep 1
  kill -INT "$pm"
  wait "$pm" || fail "sarmap-people-map exited with $? on replay $run: $(cat "$out/people_map_replay$run.txt")"
done
grep -q "position_m" "$out/replay1.yaml" || fail "nobody in the replayed people map: $(cat "$out/replay1.yaml")"
cmp -s "$out/replay1.yaml" "$out/replay2.yaml" || fail "two replays gave different people maps: $(diff "$out/replay1.yaml" "$out/replay2.yaml" | head -20)"
echo "two replays of the log through sarmap-people-map: the same $(grep -c '^  - id:' "$out/replay1.yaml") people, byte for byte"
echo "PASS"
