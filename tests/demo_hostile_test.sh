#!/usr/bin/env bash
# make demo-hostile, shortened: the dark-lab mission under the launcher while sarmap-net-fuzz
# sends crafted datagrams to every channel of the bus and 10 % of the datagrams are lost
# (launch-scripts/demo.sh DEMO_HOSTILE=1). Checks that no process of the stack crashed or was
# restarted (the launcher's signed reports), that the attack and the loss happened, that the
# simulated base refused the forged velocity commands (the demo's bus is signed: they carry no
# bus signature), and that the report was written from the log (hostile datagrams included,
# skipped with the bus key) and puts someone on the map.
# Run by CTest inside tests/harness/sarmap-netns.
set -euo pipefail
BIN="${SARMAP_BIN_DIR:?SARMAP_BIN_DIR not set}"
SRC="${SARMAP_SOURCE_DIR:?SARMAP_SOURCE_DIR not set}"
command -v iptables >/dev/null || { echo "FAIL: iptables is not installed (make deps)"; exit 1; }
out="$(mktemp -d /tmp/sarmap_demo_hostile_test_XXXXXX)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; echo "--- demo output"; cat "$out/demo.txt" || true; exit 1; }
source "$SRC/tests/harness/demo_checks.sh"

DEMO_HOSTILE=1 DEMO_SECONDS="${DEMO_TEST_SECONDS:-30}" DEMO_OUT="$out/run" \
  "$SRC/launch-scripts/demo.sh" "$BIN/.." >"$out/demo.txt" 2>&1 || fail "demo.sh exited with $?"
grep -q "the mission script failed" "$out/demo.txt" && fail "the launcher's mission script failed: $(cat "$out/run/sheriff.txt")"
sent="$(sed -nE 's/^ *sent ([0-9]+) datagrams.*/\1/p' "$out/demo.txt")"
[ -n "$sent" ] && [ "$sent" -gt 1000 ] || fail "the hostile publisher sent ${sent:-nothing}"
lost="$(sed -nE 's/^ *datagrams lost: ([0-9]+) of ([0-9]+) .*/\1/p' "$out/demo.txt")"
[ -n "$lost" ] && [ "$lost" -gt 0 ] || fail "no datagram was lost"
[ -s "$out/run/report/report.html" ] && [ -s "$out/run/report/report.json" ] || fail "the report is incomplete"
check_ran_without_restart "$out/run/perf.txt" " under the attack" sarmap-depth sarmap-slam \
  sarmap-sound-localisation sarmap-speech sarmap-vision-people sarmap-sound-map sarmap-people-map \
  sarmap-explore sarmap-viewer
for f in "$out"/run/output/*.txt; do
  if grep -aqE "terminate called|Segmentation|Aborted|core dumped|exited with code [1-9]" "$f"; then
    fail "$(basename "$f" .txt) crashed: $(grep -aE "terminate called|Segmentation|Aborted|core dumped|exited with code" "$f" | head -3)"
  fi
done
# The demo's bus is signed (every node has the bus key): forged CMD_VEL is refused before it is
# decoded, and the report counts only signed messages.
cat "$out"/run/output/*sarmap-sim.txt 2>/dev/null | grep -aq "dropped a message on CMD_VEL: not signed with the bus key" ||
  fail "the simulator refused no forged CMD_VEL"
grep -q "not signed with the bus key" "$out/demo.txt" || fail "the report skipped no unsigned message"
people="$(sed -nE 's/^mission: .*; ([0-9]+) people on the map.*/\1/p' "$out/demo.txt")"
[ -n "$people" ] && [ "$people" -ge 1 ] || fail "nobody on the map after the attacked mission"
grep -E "^ *sent |datagrams lost|^mission:|FOUND|MISSED|skipped" "$out/demo.txt"
echo "PASS"
