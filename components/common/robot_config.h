#pragma once
// Static extrinsics of a robot: where the camera and the microphone array sit on the base.
// Loaded from config/robot*.yaml, never from messages.
//
// Frames: base (x forward, y left, z up, on the floor below the rotation centre);
// camera (the optical frame of the depth camera: z forward, x right, y down, as OpenCV/PCL);
// mic_array (the frame of config/arrays/*.yaml positions).

#include <string>

#include "common/options.h"
#include "common/transform.h"

namespace sarmap {
namespace common {

struct ExtrinsicsOptions {
  double x_m = 0, y_m = 0, z_m = 0;
  double roll_rad = 0, pitch_rad = 0, yaw_rad = 0;  // applied as R = Rz(yaw) Ry(pitch) Rx(roll)
  template <class V>
  void Visit(V& v) {
    v("x_m", x_m, "translation x");
    v("y_m", y_m, "translation y");
    v("z_m", z_m, "translation z");
    v("roll_rad", roll_rad, "rotation about x");
    v("pitch_rad", pitch_rad, "rotation about y");
    v("yaw_rad", yaw_rad, "rotation about z");
  }
  Rigid3d ToRigid3d() const;
};

struct RobotOptions {
  std::string name = "pioneer-kinect";
  // Camera optical frame in the base frame. Default: a Kinect 0.55 m above the floor,
  // looking forward, level.
  ExtrinsicsOptions base_from_camera{0.10, 0.0, 0.55, -M_PI / 2, 0.0, -M_PI / 2};
  ExtrinsicsOptions base_from_mic_array{0.10, 0.0, 0.60, 0, 0, 0};
  std::string mic_array = "kinect";  // config/arrays/<name>.yaml
  double wheel_base_m = 0.38;
  double max_linear_mps = 0.5;
  double max_angular_radps = 1.0;
  template <class V>
  void Visit(V& v) {
    v("name", name, "robot name");
    v("base_from_camera", base_from_camera, "camera optical frame (z fwd, x right, y down) in base");
    v("base_from_mic_array", base_from_mic_array, "microphone array frame in base");
    v("mic_array", mic_array, "array description in config/arrays/<name>.yaml");
    v("wheel_base_m", wheel_base_m, "distance between the drive wheels", Positive());
    v("max_linear_mps", max_linear_mps, "speed limit", Positive());
    v("max_angular_radps", max_angular_radps, "turn rate limit", Positive());
  }
};

// Microphone array description, config/arrays/<name>.yaml (written by hand or by
// sarmap-mic-calibrate, read by the simulator and sarmap-sound-localisation).
struct MicArrayOptions {
  std::string name = "array";
  int sample_rate_hz = 16000;
  double speed_of_sound_mps = 343.0;
  std::string geometry = "planar";             // linear | planar | 3d
  std::vector<int> channel_map;                // device channel of each mic, in mic order
  std::vector<double> mic_positions_m;         // x0 y0 z0 x1 y1 z1 ... in the mic_array frame
  std::vector<double> mic_position_std_m;      // per mic (from calibration), or empty
  std::vector<double> start_offsets_s;         // per mic tau (asynchronous arrays), or empty
  std::vector<double> clock_drift;             // per mic fractional drift delta, or empty
  std::string sensor_model = "constant";       // constant | gp
  double doa_sigma_deg = 3.0;                  // constant model: DOA standard deviation
  std::string gp_model_file;                   // gp: trained model, relative to this file
  template <class V>
  void Visit(V& v) {
    v("name", name, "array name");
    v("sample_rate_hz", sample_rate_hz, "sample rate", AtLeast(1000));
    v("speed_of_sound_mps", speed_of_sound_mps, "speed of sound", Positive());
    v("geometry", geometry, "linear, planar or 3d", OneOf({"linear", "planar", "3d"}));
    v("channel_map", channel_map, "device channel of each microphone, in microphone order");
    v("mic_positions_m", mic_positions_m, "x y z of each microphone (flattened), mic_array frame");
    v("mic_position_std_m", mic_position_std_m, "per-microphone position std (calibration), or []");
    v("start_offsets_s", start_offsets_s, "per-microphone start offset tau (asynchronous), or []");
    v("clock_drift", clock_drift, "per-microphone fractional clock drift delta, or []");
    v("sensor_model", sensor_model, "constant or gp", OneOf({"constant", "gp"}));
    v("doa_sigma_deg", doa_sigma_deg, "constant sensor model: DOA std in degrees", Positive());
    v("gp_model_file", gp_model_file, "gp sensor model file, relative to this file");
  }
  void Validate(Validator& check) const;
  int num_mics() const { return static_cast<int>(mic_positions_m.size() / 3); }
  Eigen::Vector3d mic_position(int i) const {
    return Eigen::Vector3d(mic_positions_m[3 * i], mic_positions_m[3 * i + 1], mic_positions_m[3 * i + 2]);
  }
};

// Finds a configuration file: `path` as given when it exists (or is absolute), else relative
// to the source tree's config/ (so nodes run from any directory find config/robot.yaml). Returns `path` unchanged when found nowhere, so the
// loader's error names what was asked for.
std::string ResolveConfigPath(const std::string& path);

// Loads config/robot*.yaml and config/arrays/<name>.yaml (path given directly).
RobotOptions LoadRobot(const std::string& path, const std::vector<std::string>& overrides = {});
MicArrayOptions LoadMicArray(const std::string& path, const std::vector<std::string>& overrides = {});

}  // namespace common
}  // namespace sarmap
