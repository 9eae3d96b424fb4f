#!/usr/bin/env bash
# Autonomous exploration in closed loop over real LCM: sarmap-sim (a small generated site, driven
# by CMD_VEL), sarmap-depth, sarmap-slam and sarmap-explore as separate processes, recorded by
# sarmap-log record. The mission report of the log must show >= 75 % of the reachable floor
# mapped and at most one contact. The processes run in real time, so one run differs from the
# next: on this site SLAM now and then loses the robot by a metre for a while (a stationary robot
# facing a bare wall), which ends the exploration early with 80-85 % mapped; most runs map
# 96-98 %. The explorer passes walls and furniture with 1-3 cm to spare (its closest approach
# in sarmap-mission-bench, components/explore/README.md), so now and then a run touches one
# (1 contact in some runs); more than one fails the test. Every contact is printed.
# Coverage itself is measured deterministically by sarmap-mission-bench (components/explore).
# Run by CTest inside tests/harness/sarmap-netns.
set -euo pipefail
BIN="${SARMAP_BIN_DIR:?SARMAP_BIN_DIR not set}"
SRC="${SARMAP_SOURCE_DIR:?SARMAP_SOURCE_DIR not set}"
SECONDS_SIM="${EXPLORE_TEST_SECONDS:-180}"
out="$(mktemp -d /tmp/sarmap_explore_test_XXXXXX)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  sleep 1
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  rm -rf "$out"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in "$out"/*.txt; do echo "--- $(basename "$f")"; tail -n 15 "$f"; done
  exit 1
}
cd "$SRC"

"$BIN/sarmap-site" --seed 2 --set floor_area_m2=70 --set people_min=1 --set people_max=2 -o "$out/site.yaml" \
  >"$out/site.txt" 2>&1 || fail "sarmap-site failed"
"$BIN/sarmap-log" record -o "$out/mission.lcmlog" --force >"$out/record.txt" 2>&1 & pids+=($!)
"$BIN/sarmap-slam" --config config/slam_kinect_robot.yaml >"$out/slam.txt" 2>&1 & pids+=($!)
"$BIN/sarmap-depth" --set source=lcm >"$out/depth.txt" 2>&1 & pids+=($!)
"$BIN/sarmap-explore" --set explore.mode=frontier >"$out/explore.txt" 2>&1 & pids+=($!)
sleep 2
"$BIN/sarmap-sim" --world "$out/site.yaml" --duration "$SECONDS_SIM" --speed 1 --set drive=cmd_vel \
  --set audio.enabled=false >"$out/sim.txt" 2>&1 || fail "sarmap-sim failed"
sleep 1
for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
pids=()
"$BIN/sarmap-log" report "$out/mission.lcmlog" -o "$out/report" >"$out/report.txt" 2>&1 || fail "sarmap-log report failed"
python3 - "$out/report/report.json" <<'PY' || fail "mission figures below the goal"
import json, sys
r = json.load(open(sys.argv[1]))
c = r["coverage"]
print(f"reachable {c['reachable_m2']:.1f} m^2, mapped {100 * c['mapped_fraction']:.1f} %, "
      f"collisions {r['collisions']}, came home {r['came_home']}, longest stuck {r['longest_stuck_s']} s")
ok = c["mapped_fraction"] >= 0.75 and r["collisions"] <= 1
sys.exit(0 if ok else 1)
PY
grep -h "collision" "$out/sim.txt" || true
echo "PASS"
