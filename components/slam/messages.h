#pragma once
// sarmap messages <-> SLAM core types (header-only; for the node and the offline runner).

#include <cmath>

#include "common/message_conversions.h"
#include "common/time.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
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

// SLAM_ANCHORS: the nodes `ids` (the current one first) with their poses and their joint
// covariance `cov` (3 x ids.size() square, x y yaw per node).
inline slam_anchors_t AnchorsMessage(const Slam& slam, const std::vector<int>& ids, const Eigen::MatrixXd& cov,
                                     bool loop_closed) {
  slam_anchors_t msg{};
  msg.header.utime = common::SecondsToUtime(slam.NodeTime(ids[0]));
  msg.header.frame = "map";
  msg.optimisation_id = slam.optimisation_id();
  msg.loop_closed = loop_closed;
  auto anchor = [&](int id) {
    slam_anchor_t a{};
    a.node_id = id;
    a.utime = common::SecondsToUtime(slam.NodeTime(id));
    const Rigid2d p = slam.NodePose(id);
    a.x_m = p.translation().x();
    a.y_m = p.translation().y();
    a.yaw_rad = p.yaw_rad();
    return a;
  };
  msg.current = anchor(ids[0]);
  for (size_t i = 1; i < ids.size(); ++i) msg.anchors.push_back(anchor(ids[i]));
  msg.num_anchors = static_cast<int32_t>(msg.anchors.size());
  msg.covariance_dim = static_cast<int32_t>(3 * ids.size());
  msg.covariance.assign(msg.covariance_dim, std::vector<double>(msg.covariance_dim));
  for (int r = 0; r < msg.covariance_dim; ++r) {
    for (int c = 0; c < msg.covariance_dim; ++c) msg.covariance[r][c] = cov(r, c);
  }
  return msg;
}

inline Rigid2d FromOdometryMessage(const odometry_t& msg) {
  return common::ToRigid3d(msg.position_m, msg.orientation).ToRigid2d();
}

}  // namespace slam
}  // namespace sarmap
