#pragma once
// The people detector (components/vision_people) on the simulator's lab (issue 7's simulated
// acceptance), shared by bench_sim_vision (prints) and sim_vision_test (asserts).
//
// Frames are rendered every step_s along the world's scripted robot path. A person counts as
// fully visible when at least 1500 of its body pixels are in the depth image, its box lies
// inside the depth's field of view (narrower than the colour image's; 2 px in from its
// border) and it stands within the camera's depth range (4.6 m, floor distance from the
// camera to the person's centre); it is found when a detection lies within 0.5 m
// of it on the floor (map frame). A detection within 0.5 m of no person is a false positive.
#include <cstdint>
#include <string>
#include <vector>

namespace sarmap {
namespace sim_vision {

struct EvalOptions {
  std::string world = "lab_lit";       // config/worlds/<world>.yaml
  double seconds = 40.0;               // simulated time covered
  double step_s = 0.5;                 // between evaluated frames
  int64_t seed = 1;                    // simulator noise
  std::vector<std::string> overrides;  // key=value on config/vision_people.yaml
  bool verbose = false;                // per person and per non-person candidate lines
  // The simulated camera's mounting (config/robot.yaml's otherwise); the detector is still
  // told config/robot.yaml's (a mounting file that disagrees with the robot).
  double camera_height_m = -1;      // < 0: robot.yaml's
  double camera_tilt_down_deg = 0;  // with camera_height_m >= 0: looking down by this
  // > 0: instead of following the scripted path, the robot stays at its start pose and turns
  // by this much between evaluated frames (as an exploring robot does when it starts).
  double spin_deg_per_step = 0;
};

// Per posture (index: sim::Posture - 1: standing, sitting, lying).
struct PostureFigures {
  int visible = 0, found = 0;
};

struct Figures {
  int frames = 0;
  int visible = 0;          // fully visible person-frames
  int found = 0;            // ... with a detection in that frame
  int false_positives = 0;  // detections near nobody, over all frames
  PostureFigures by_posture[3];
  // The same after the node's k-of-n confirmation run on these frames (step_s apart, so a
  // track needs k * step_s of simulated time, not k camera frames).
  int confirm_k = 0, confirm_n = 0;
  int confirmed_found = 0;
  int confirmed_false_positives = 0;
  double detect_cpu_ms_mean = 0, detect_cpu_ms_max = 0;  // PeopleDetector::Detect, CPU time
  // Found fully visible people: the detection's range from the camera on the floor minus the
  // person's (positive: placed beyond them), and its error across the line of sight.
  int placed = 0;
  double range_error_sum_m = 0, range_error_sq_sum_m2 = 0, cross_error_sq_sum_m2 = 0;
  double range_bias_m() const { return placed ? range_error_sum_m / placed : 0.0; }
  double recall() const { return visible ? static_cast<double>(found) / visible : 0.0; }
  double fp_per_frame() const {
    return frames ? static_cast<double>(false_positives) / frames : 0.0;
  }
  double confirmed_recall() const {
    return visible ? static_cast<double>(confirmed_found) / visible : 0.0;
  }
  double confirmed_fp_per_frame() const {
    return frames ? static_cast<double>(confirmed_false_positives) / frames : 0.0;
  }
};

// Runs one world. Throws on a bad world or options file.
Figures Evaluate(const EvalOptions& options);

}  // namespace sim_vision
}  // namespace sarmap
