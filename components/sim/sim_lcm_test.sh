#!/usr/bin/env bash
# Multi-process test (inside sarmap-netns): sarmap-sim publishes on real LCM, faster than
# real time, and sim_lcm_check sees every channel at its rate with valid headers, and the
# robot follows the CMD_VEL it publishes.
set -euo pipefail
bin="${SARMAP_BIN_DIR:?}"
src="${SARMAP_SOURCE_DIR:?}"
"$bin/sim_lcm_check" --seconds 3 --timeout 60 --cmd-vel 0.3 &
checker=$!
sleep 0.5
"$bin/sarmap-sim" --config "$src/config/sim.yaml" --set "data_dir=${SARMAP_DATA_DIR:-../shared/data}" \
  --set drive=cmd_vel --speed 2 --duration 3.5 --log-level warn
wait "$checker"
