#pragma once
// sarmap messages <-> SLAM core types (header-only; for the node and the offline runner).

#include <cmath>

#include "common/message_conversions.h"
#include "common/time.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "slam/slam.h"

namespace sarmap {
namespace slam {

inline LaserScan FromScanMessage(const laser_scan_t& msg) {
  LaserScan s;
  s.time_s = common::UtimeToSeconds(msg.header.utime);
  s.angle_min_rad = msg.angle_min_rad;
  s.angle_increment_rad = msg.angle_increment_rad;
  s.range_min_m = msg.range_min_m;
  s.range_max_m = msg.range_max_m;
  s.ranges_m = msg.ranges_m;
  return s;
}

inline Rigid2d FromOdometryMessage(const odometry_t& msg) {
  return common::ToRigid3d(msg.position_m, msg.orientation).ToRigid2d();
}

}  // namespace slam
}  // namespace sarmap
