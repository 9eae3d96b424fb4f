#pragma once
// The options of sarmap-vision-people (config/vision_people.yaml): channels, where the camera
// is mounted, the detector and the multi-frame confirmation.

#include <cmath>
#include <string>
#include <vector>

#include "common/options.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "vision_people/confirmation_tracker.h"
#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

struct VisionPeopleOptions {
  std::string depth_channel = "DEPTH";
  std::string rgb_channel = "RGB";
  std::string output_channel = "PEOPLE_VISUAL";
  std::string sensor_id = "kinect";
  std::string robot_config = "config/robot.yaml";  // base_from_camera seeds the floor
  // Floor as a x + b y + c z + d = 0 in the camera frame; empty: from robot_config's mounting.
  std::vector<double> ground_coefficients;
  // The mounting as a user measures it (> 0 height: instead of robot_config's base_from_camera).
  double camera_height_m = 0;       // optical centre above the floor
  double camera_tilt_down_deg = 0;  // optical axis below the horizon (negative: looking up)
  double camera_roll_deg = 0;       // about the optical axis
  double max_pair_dt_s = 0.02;      // depth and colour closer than this in utime form a pair
  double color_wait_s = 0.1;        // a depth frame waits this long (message time) for its colour
  bool require_color = false;       // false: depth frames without colour are processed depth-only
  double max_rate_hz = 0;           // frames processed per second of stamps at most (0: every one)
  DetectorOptions detector;
  ConfirmationOptions confirmation;
  common::StampGateOptions stamp_gate;  // DEPTH and RGB, each on its own clock
  template <class V>
  void Visit(V& v) {
    v("depth_channel", depth_channel, "depth image_t channel");
    v("rgb_channel", rgb_channel, "colour image_t channel (registered to the depth)");
    v("output_channel", output_channel, "people_detections_t channel");
    v("sensor_id", sensor_id, "sensor_id written into the detections");
    v("robot_config", robot_config, "robot description whose base_from_camera seeds the floor");
    v("ground_coefficients", ground_coefficients,
      "fixed floor a b c d in the camera frame ([] = from robot_config)");
    v("camera_height_m", camera_height_m,
      "camera height above the floor (> 0: used instead of robot_config's mounting)",
      NonNegative());
    v("camera_tilt_down_deg", camera_tilt_down_deg,
      "with camera_height_m: optical axis below the horizon, degrees (negative: up)",
      InRange(-89, 89));
    v("camera_roll_deg", camera_roll_deg,
      "with camera_height_m: roll about the optical axis, degrees", InRange(-89, 89));
    v("max_pair_dt_s", max_pair_dt_s, "depth and colour closer in time than this are a pair",
      NonNegative());
    v("color_wait_s", color_wait_s, "how long (message time) a depth frame waits for its colour",
      NonNegative());
    v("require_color", require_color,
      "drop depth frames without colour instead of going depth-only");
    v("max_rate_hz", max_rate_hz,
      "process at most this many frames per second (by their stamps; the rest are skipped and "
      "counted); 0: every frame",
      NonNegative());
    v("detector", detector, "people detector");
    v("confirmation", confirmation, "k-of-n multi-frame confirmation");
    v("stamp_gate", stamp_gate,
      "depth and colour frames stamped far from their stream's clock are dropped (common/stamp_gate.h)");
  }
  void Validate(common::Validator& check) const {
    check.That(ground_coefficients.empty() || ground_coefficients.size() == 4,
               "ground_coefficients", "must be empty or a b c d");
  }
};

// The floor the detector starts from (a prior: the floor is found in the data): ground_coefficients
// when given, else camera_height_m / camera_tilt_down_deg / camera_roll_deg when the height is
// set, else the floor seen from robot_config's base_from_camera. Throws common::OptionsError
// on a bad robot file.
inline GroundPlane InitialGround(const VisionPeopleOptions& options) {
  if (options.ground_coefficients.size() == 4) {
    const auto& g = options.ground_coefficients;
    return GroundPlane::FromCoefficients(Eigen::Vector4d(g[0], g[1], g[2], g[3]));
  }
  if (options.camera_height_m > 0) {
    constexpr double kDeg = M_PI / 180;
    return GroundFromCameraMounting({options.camera_height_m, options.camera_tilt_down_deg * kDeg,
                                     options.camera_roll_deg * kDeg});
  }
  const common::RobotOptions robot = common::LoadRobot(options.robot_config);
  const common::Rigid3d base_from_camera = robot.base_from_camera.ToRigid3d();
  return GroundFromMounting(base_from_camera.rotation().toRotationMatrix(),
                            base_from_camera.translation());
}

}  // namespace vision_people
}  // namespace sarmap
