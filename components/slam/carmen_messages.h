#pragma once
// CARMEN records <-> sarmap messages (header-only, used by the import tool and offline runner).

#include <cmath>
#include <limits>

#include "common/time.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "slam/carmen.h"

namespace sarmap {
namespace slam {

inline odometry_t ToOdometryMessage(const CarmenOdometry& o) {
  odometry_t msg{};
  msg.header.utime = common::SecondsToUtime(o.time_s);
  msg.header.frame = "odom";
  msg.child_frame = "base";
  msg.position_m[0] = o.x_m;
  msg.position_m[1] = o.y_m;
  msg.orientation[0] = std::cos(o.theta_rad / 2);
  msg.orientation[3] = std::sin(o.theta_rad / 2);
  msg.linear_velocity_mps[0] = o.tv_mps;
  msg.angular_velocity_radps[2] = o.rv_radps;
  return msg;
}

inline laser_scan_t ToScanMessage(const CarmenLaser& l) {
  laser_scan_t msg{};
  msg.header.utime = common::SecondsToUtime(l.time_s);
  msg.header.frame = "laser";
  msg.angle_min_rad = l.angle_min_rad;
  msg.angle_increment_rad = l.angle_increment_rad;
  msg.range_min_m = 0.0f;
  // laser_scan_t: a range outside [min, max] is no return; CARMEN's max reading is one.
  msg.range_max_m = std::nextafter(static_cast<float>(l.range_max_m), 0.0f);
  msg.num_ranges = static_cast<int32_t>(l.ranges_m.size());
  msg.ranges_m = l.ranges_m;
  msg.num_intensities = 0;
  return msg;
}

}  // namespace slam
}  // namespace sarmap
