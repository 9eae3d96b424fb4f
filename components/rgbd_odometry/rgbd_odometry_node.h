#pragma once
// RgbdOdometryNode: the LCM adapter of RGB-D odometry. DEPTH (+ RGB for the photometric
// methods, paired by utime) in, RIG_POSE (pose_t, odom_from_rig in the body convention x
// forward, y left, z up) out, around RgbdOdometry (rgbd_odometry.h). Time going back by more
// than a second (a log replayed again) starts the odometry over.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/logging.h"
#include "common/node.h"
#include "rgbd_odometry/frame_assembler.h"
#include "rgbd_odometry/rgbd_odometry.h"
#include "rgbd_odometry/rgbd_odometry_node_options.h"

namespace sarmap {
namespace rgbd_odometry {

class RgbdOdometryNode {
 public:
  RgbdOdometryNode(const RgbdOdometryNodeOptions& options, common::Node* node);

  int64_t published() const { return published_; }
  const RgbdOdometry& odometry() const { return odometry_; }
  // Frame-pairing warnings by kind (FrameAssembler::warnings).
  const std::map<std::string, int64_t>& pairing_warnings() const { return assembler_.warnings(); }

  // For replay tools: called with every frame's odometry result (tracked, lost or invalid).
  using ResultObserver = std::function<void(const RgbdOdometryResult&)>;
  void set_result_observer(ResultObserver observer) { observer_ = std::move(observer); }

 private:
  void Process();
  void UpdateStatus();

  RgbdOdometryNodeOptions options_;
  common::Node* node_;
  RgbdOdometry odometry_;
  FrameAssembler assembler_;
  common::Node::Publisher<pose_t> publisher_;
  common::RateLimiter warn_limit_{2.0};
  std::vector<RgbdFrame> ready_;
  int64_t last_warnings_ = 0, published_ = 0, last_utime_ = 0;
  double total_ms_ = 0;
  TrackingStatus last_status_ = TrackingStatus::kInvalidInput;
  std::string last_status_name_ = "waiting";
  ResultObserver observer_;
};

}  // namespace rgbd_odometry
}  // namespace sarmap
