#pragma once
// sarmap-mic-calibrate's options (config/mic_calibrate.yaml).
#include <string>

#include "common/options.h"
#include "mic_calibrate/calibration.h"
#include "mic_calibrate/tdoa_extraction.h"

namespace sarmap {
namespace mic_calibrate {

// Known array motion (CalibrateWithArrayPoses): the robot carrying the array turned/drove
// while one source stood still; the poses of the base come from a channel of an LCM log.
struct ArrayPosesOptions {
  std::string channel;                             // "" = off; ODOM, POSE or SIM_TRUTH
  std::string robot_config = "config/robot.yaml";  // base_from_mic_array
  double max_gap_s = 0.25;                         // an emission this far from any pose is dropped
  template <class V>
  void Visit(V& v) {
    v("channel", channel,
      "pose channel (odometry_t, pose_t or sim_truth_t) of the robot carrying the array while "
      "a static source sounded; empty = off (the source moved around a static array)");
    v("robot_config", robot_config, "robot YAML with base_from_mic_array");
    v("max_gap_s", max_gap_s, "largest time from an emission to a pose (interpolation)",
      Positive());
  }
};

struct MicCalibrateOptions {
  std::string array_name = "calibrated";
  double step_s = 0.5;  // TDOA CSV without t_s: t_k = k * step_s (thesis: a chirp every 0.5 s)
  std::string lcm_channel_prefix = "AUDIO";
  SolverOptions solver;
  ExtractionOptions extraction;
  ArrayPosesOptions array_poses;
  template <class V>
  void Visit(V& v) {
    v("array_name", array_name, "name written into the array YAML");
    v("step_s", step_s, "TDOA CSV without t_s column: seconds between steps k", Positive());
    v("lcm_channel_prefix", lcm_channel_prefix, "LCM log input: audio channels with this prefix");
    v("solver", solver, "graph least-squares calibration");
    v("extraction", extraction, "TDOA extraction from audio");
    v("array_poses", array_poses, "known array motion with a static source");
  }
};

}  // namespace mic_calibrate
}  // namespace sarmap
