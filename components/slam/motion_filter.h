#pragma once
// Which scans become graph nodes (Cartographer's MotionFilter): a scan whose local pose is
// further than local.node_max_distance_m or node_max_angle_deg from the last node's, or later
// than node_max_time_s after it. The others are matched and published but not inserted.

#include <cmath>

#include "common/transform.h"
#include "slam/slam_options.h"

namespace sarmap {
namespace slam {

class MotionFilter {
 public:
  explicit MotionFilter(const LocalOptions& options) : options_(options) {}

  // Whether a scan at `time_s`, `local_pose` moved enough since the last node (before the
  // first node: its time is -1e300 s, so always).
  bool Moved(double time_s, const common::Rigid2d& local_pose) const {
    return time_s - last_time_s_ > options_.node_max_time_s ||
           (local_pose.translation() - last_pose_.translation()).norm() >
               options_.node_max_distance_m ||
           std::abs(std::remainder(local_pose.yaw_rad() - last_pose_.yaw_rad(), 2 * M_PI)) >
               options_.node_max_angle_deg * M_PI / 180.0;
  }
  // The scan became a node: later scans are measured from it.
  void NodeAdded(double time_s, const common::Rigid2d& local_pose) {
    last_time_s_ = time_s;
    last_pose_ = local_pose;
  }
  // Back to a saved state's last node.
  void Restore(double time_s, const common::Rigid2d& local_pose) {
    last_time_s_ = time_s;
    last_pose_ = local_pose;
  }
  double last_time_s() const { return last_time_s_; }
  const common::Rigid2d& last_pose() const { return last_pose_; }

 private:
  LocalOptions options_;
  double last_time_s_ = -1e300;
  common::Rigid2d last_pose_;
};

}  // namespace slam
}  // namespace sarmap
