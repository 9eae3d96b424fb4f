#pragma once
// Reader for CARMEN text logs (the Freiburg / Radish SLAM benchmark format).
//
// Understood lines (anything else, and '#' comments, are skipped and counted):
//   ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp
//   FLASER n r_1..r_n x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp
//       (front laser, 180 deg field of view starting at -90 deg; odometry inside the line)
//   RAWLASER1 type start_angle fov angular_res max_range accuracy remission_mode
//       n r_1..r_n n_rem rem_1..rem_n_rem ipc_timestamp hostname logger_timestamp
//   ROBOTLASER1 type start_angle fov angular_res max_range accuracy remission_mode
//       n r_1..r_n n_rem rem.. laser_x laser_y laser_theta robot_x robot_y robot_theta
//       tv rv forward_safety side_safety turn_axis ipc_timestamp hostname logger_timestamp
// Timestamps are the ipc_timestamp (seconds), as the .relations files use them.

#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <vector>

namespace sarmap {
namespace slam {

struct CarmenOdometry {
  double time_s = 0;
  double x_m = 0, y_m = 0, theta_rad = 0;  // odom_from_base
  double tv_mps = 0, rv_radps = 0;
};

struct CarmenLaser {
  double time_s = 0;
  double angle_min_rad = 0;
  double angle_increment_rad = 0;
  double range_max_m = 0;  // readings at or beyond this are "no return"
  std::vector<float> ranges_m;
  std::vector<float> remissions;
  // Odometry carried by FLASER / ROBOTLASER1 lines (has_odometry), else none.
  bool has_odometry = false;
  CarmenOdometry odometry;
  // ROBOTLASER1: laser pose relative to the robot (base_from_laser), else identity.
  double base_from_laser_x_m = 0, base_from_laser_y_m = 0, base_from_laser_yaw_rad = 0;
  std::string source;  // "FLASER", "RAWLASER1", "ROBOTLASER1"
};

struct CarmenStats {
  int64_t lines = 0;
  int64_t odometry = 0;
  int64_t lasers = 0;
  int64_t skipped_comments = 0;
  int64_t skipped_unknown = 0;  // other message types (PARAM, SYNC, ...)
  int64_t malformed = 0;        // known type but unparsable
};

// Streams a CARMEN log, calling the callbacks in file order. Malformed lines are counted
// (and the first few reported through `warn`), never fatal.
class CarmenReader {
 public:
  std::function<void(const CarmenOdometry&)> on_odometry;
  std::function<void(const CarmenLaser&)> on_laser;
  std::function<void(const std::string&)> warn;  // optional
  // Called every ~1 MB of input with (bytes read so far).
  std::function<void(int64_t)> on_progress;

  CarmenStats Read(std::istream& in);
  // Parses one line; returns false if it is a known type that could not be parsed.
  bool ParseLine(const std::string& line, CarmenStats* stats);
};

// Reads a whole file; throws std::runtime_error if it cannot be opened.
CarmenStats ReadCarmenFile(const std::string& path, CarmenReader* reader);

}  // namespace slam
}  // namespace sarmap
