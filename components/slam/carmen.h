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
// Geometry: RAWLASER1 / ROBOTLASER1 lines carry their own start angle and resolution (beam i at
// start_angle + i * angular_res), so consecutive lines may differ (interlacing scanners); the
// fov field is not used. FLASER lines carry none: 180 deg from -90 deg, beams at both ends.

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

// Interlacing, to test scanners whose geometry changes from scan to scan (a SICK LMS interlaces:
// 181 beams from -90 deg, then 180 beams from -89.75, -89.5, -89.25 deg). Scan k of a log is cut
// to phase k % kInterlacePhases of its own sweep of n beams (start a, increment d):
//   0: all n beams from a;                  1: beams 1..n-1, n-1 beams from a + d;
//   2: even beams, ceil(n/2) from a, 2 d;   3: odd beams, floor(n/2) from a + d, 2 d.
// Every kept reading stays at its exact angle, so the cut log keeps the original's accuracy
// up to the information dropped.
constexpr int kInterlacePhases = 4;
CarmenLaser InterlacedLaser(const CarmenLaser& laser, int phase);

// CARMEN lines (no trailing newline): ODOM, and a laser as RAWLASER1 (ROBOTLASER1 when it was
// one, with its odometry and laser pose), with its own start angle, fov and resolution. A
// FLASER's odometry is not in a RAWLASER1 line: write it as an ODOM line before it.
std::string FormatCarmenOdometry(const CarmenOdometry& odometry);
std::string FormatCarmenLaser(const CarmenLaser& laser);

}  // namespace slam
}  // namespace sarmap
