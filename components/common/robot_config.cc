#include "common/robot_config.h"

#include <unistd.h>

#include <cstdlib>

namespace sarmap {
namespace common {

Rigid3d ExtrinsicsOptions::ToRigid3d() const {
  const Eigen::Quaterniond rotation = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                                      Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX());
  return Rigid3d(Eigen::Vector3d(x_m, y_m, z_m), rotation);
}

void MicArrayOptions::Validate(Validator& check) const {
  check.That(mic_positions_m.size() % 3 == 0 && mic_positions_m.size() >= 6, "mic_positions_m",
             "must hold x y z for at least 2 microphones");
  const size_t n = mic_positions_m.size() / 3;
  check.That(channel_map.empty() || channel_map.size() == n, "channel_map",
             "must be empty or have one entry per microphone");
  for (int c : channel_map) check.That(c >= 0, "channel_map", "channels are >= 0");
  check.That(mic_position_std_m.empty() || mic_position_std_m.size() == n, "mic_position_std_m",
             "must be empty or have one entry per microphone");
  check.That(start_offsets_s.empty() || start_offsets_s.size() == n, "start_offsets_s",
             "must be empty or have one entry per microphone");
  check.That(clock_drift.empty() || clock_drift.size() == n, "clock_drift",
             "must be empty or have one entry per microphone");
  check.That(sensor_model != "gp" || !gp_model_file.empty(), "gp_model_file",
             "needed when sensor_model is gp");
}

std::string ResolveConfigPath(const std::string& path) {
  if (path.empty() || path[0] == '/' || access(path.c_str(), R_OK) == 0) return path;
  std::string relative = path;
  if (relative.rfind("config/", 0) == 0) relative = relative.substr(7);
  const std::string candidate = std::string(SARMAP_DEFAULT_CONFIG_DIR) + "/" + relative;
  if (access(candidate.c_str(), R_OK) == 0) return candidate;
  return path;
}

RobotOptions LoadRobot(const std::string& path, const std::vector<std::string>& overrides) {
  return LoadOptions<RobotOptions>(ResolveConfigPath(path), overrides);
}

MicArrayOptions LoadMicArray(const std::string& path, const std::vector<std::string>& overrides) {
  return LoadOptions<MicArrayOptions>(ResolveConfigPath(path), overrides);
}

}  // namespace common
}  // namespace sarmap
