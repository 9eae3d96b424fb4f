#!/bin/sh
# End to end with the simulator (issue 8): record an asynchronous Kinect-like array (four
# single-mic sound cards with the start offsets and drifts of config/arrays/async_kinect.yaml)
# while the robot drives a star around a source of noise bursts, calibrate the offsets and
# drifts from the LCM log with the Kinect's known geometry, and compare with the truth.
#
#   components/mic_calibrate/sim/e2e_async_kinect.sh [BUILD_BIN_DIR] [OUT_DIR] [DURATION_S]
#
# METHOD (default poses):
#   poses  the array's motion is known (the robot's ODOM, with the simulator's odometry noise
#          model as a pose graph) and the noise source stands still: one source position,
#          offsets and drifts (CalibrateWithArrayPoses). Needed for the Kinect-like array: with
#          the microphones on one line and an unknown source path, clock errors growing along
#          the line look like a rotation of every direction (10 deg off with METHOD=path).
#   path   the source path is unknown (random-walk prior, thesis ch. 3) and the positions known.
# POSE_CHANNEL=SIM_TRUTH uses the true poses instead (as from a good SLAM; no pose graph).
# SIM_SEED=n records with another simulator seed (noise, odometry drift, jitter).
# WORLD=turn_in_place_world.yaml: the robot turns on the spot 1.5 m from the source instead of
# driving the star (METHOD=poses only: the source is not seen from every side of the array).
# METHOD=path ARRAY=async6 SYNC_ARRAY=sync6 GEOMETRY=3d EXTRA="--set solver.sources_in_gauge_plane=true"
# runs the six-card 3D array (the source is at the array's height).
#
# The log is written directly by the simulator through LCM's file provider (no network).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
bin=${1:-$repo/build/bin}
out=${2:-/tmp/sarmap_e2e_calib}
duration=${3:-250}
cal_end=205   # the noise bursts stop here (world file); the talker follows
array=${ARRAY:-async_kinect}
sync_array=${SYNC_ARRAY:-kinect}
EXTRA=${EXTRA:-}   # more --set options for the solver
method=${METHOD:-poses}
sim_seed=${SIM_SEED:-1}
world=${WORLD:-calibration_world.yaml}
if [ "$method" = poses ]; then geometry=${GEOMETRY:-linear}; else geometry=${GEOMETRY:-planar}; fi
pose_channel=${POSE_CHANNEL:-ODOM}
if [ "$method" = poses ]; then
  # The robot's poses during the recording (same log); with ODOM the simulator's odometry
  # noise (components/sim OdometryOptions defaults) is the pose graph's edge noise.
  if [ "$pose_channel" = ODOM ]; then
    pose_noise="--set solver.pose_trans_sigma_per_sqrt_m=0.02 --set solver.pose_rot_sigma_per_sqrt_rad=0.02 --set solver.pose_rot_sigma_per_sqrt_m=0.005"
  else
    pose_noise=""
  fi
  cal_opts="--set array_poses.channel=$pose_channel --poses $out/$array.lcmlog $pose_noise $EXTRA"
else
  cal_opts="--set solver.known_positions=true $EXTRA"
fi
mkdir -p "$out"
cd "$repo"
if [ ! -s "$out/$array.lcmlog" ]; then
  "$bin/sarmap-sim" --world "$here/$world" \
    --set audio.mic_array=config/arrays/$array.yaml --set audio.asynchronous=true \
    --set camera.enabled=false --set seed=$sim_seed --speed 0 --duration "$duration" \
    --lcm-url "file://$out/$array.lcmlog?mode=w" --log-level warn
fi
if [ ! -s "$out/${sync_array}_sync.lcmlog" ]; then   # the same scene with the synchronous Kinect
  "$bin/sarmap-sim" --world "$here/$world" \
    --set audio.mic_array=config/arrays/$sync_array.yaml --set audio.asynchronous=false \
    --set camera.enabled=false --set seed=$sim_seed --speed 0 --duration "$duration" \
    --lcm-url "file://$out/${sync_array}_sync.lcmlog?mode=w" --log-level warn
fi
# All of the log (the talker included) with the source path unknown: extracts the TDOAs.
"$bin/sarmap-mic-calibrate" "$out/$array.lcmlog" --config config/mic_calibrate.yaml \
  --set solver.geometry=$geometry --set solver.known_positions=true $EXTRA \
  --set solver.speed_of_sound_mps=343 --set solver.tdoa_sigma_s=0.00005 --set array_name=${array}_calibrated \
  --nominal config/arrays/$sync_array.yaml --output "$out/${array}_all.yaml" \
  --report "$out/${array}_all_report" --write-tdoa "$out/${array}_tdoa.csv" --quiet
# Calibrate from the noise-burst part only (the talker part is the test).
awk -F, -v end="$cal_end" '/^#/ || /^k/ { print; next } $2 <= end { print }' \
  "$out/${array}_tdoa.csv" > "$out/${array}_tdoa_calibration.csv"
"$bin/sarmap-mic-calibrate" "$out/${array}_tdoa_calibration.csv" --config config/mic_calibrate.yaml \
  --set solver.geometry=$geometry $cal_opts \
  --set solver.speed_of_sound_mps=343 --set solver.tdoa_sigma_s=0.00005 --set array_name=${array}_calibrated \
  --nominal config/arrays/$sync_array.yaml --output "$out/${array}_calibrated.yaml" \
  --report "$out/${array}_report" --quiet
echo "calibrated: $out/${array}_calibrated.yaml"
# Truth. The log reader puts every card on the reference's time line by the utime of its
# first sample (median over blocks of utime - index / rate), which the simulator stamps with
# the card's true capture time (so its start offset tau_i is taken out) plus +-1 ms jitter; the
# median over a card's blocks lands mid-recording, where the card's clock has drifted by
# delta_i * (T/2 + tau_i). What remains for the calibration: drift delta_i, and an offset of
# about -delta_i * (T/2 + tau_i) (+- a few 0.01 ms of median jitter).
awk -v T="$duration" '
  FNR == 1 { file++ }
  file == 1 && /^start_offsets_s:/ { gsub(/[][,]/, " "); for (i = 2; i <= NF; i++) tt[i-1] = $i }
  file == 1 && /^clock_drift:/ { gsub(/[][,]/, " "); for (i = 2; i <= NF; i++) td[i-1] = $i }
  file == 2 && /^start_offsets_s:/ { gsub(/[][,]/, " "); for (i = 2; i <= NF; i++) et[i-1] = $i; n = NF - 1 }
  file == 2 && /^clock_drift:/ { gsub(/[][,]/, " "); for (i = 2; i <= NF; i++) ed[i-1] = $i }
  END {
    printf "card  injected tau [ms]  delta [us/s] | estimated delta [us/s]  err | expected tau [ms]  estimated  err\n"
    for (i = 2; i <= n; i++) {
      exp_tau = -td[i] * (T / 2 + tt[i]);
      printf "%4d  %10.3f  %10.3f | %10.4f  %8.4f | %8.4f  %8.4f  %8.4f\n", i, tt[i] * 1e3, td[i] * 1e6,
             ed[i] * 1e6, (ed[i] - td[i]) * 1e6, exp_tau * 1e3, et[i] * 1e3, (et[i] - exp_tau) * 1e3
    }
  }' config/arrays/$array.yaml "$out/${array}_calibrated.yaml"
# The talker part: DOA of the calibrated asynchronous array against the synchronous array.
"$bin/sarmap-mic-calibrate-doa-check" "$out/${sync_array}_sync.lcmlog" "$out/$array.lcmlog" \
  "$out/${array}_calibrated.yaml" --array config/arrays/$sync_array.yaml --from-s $((cal_end + 5))
