#include "rgbd_odometry/rgbd_odometry_node.h"

#include <sstream>

#include "common/message_conversions.h"

namespace sarmap {
namespace rgbd_odometry {

RgbdOdometryNode::RgbdOdometryNode(const RgbdOdometryNodeOptions& options, common::Node* node)
    : options_(options),
      node_(node),
      odometry_(options.odometry),
      assembler_(odometry_.needs_image(), options.max_pair_dt_s, options.color_wait_s),
      publisher_(node->Advertise<pose_t>(options.pose_channel)) {
  UpdateStatus();
  // Odometry wants the newest frames: a short queue lets LCM drop old ones when behind.
  node->Subscribe<image_t>(
      options_.depth_channel,
      [this](const image_t& m, const common::ReceiveInfo&) {
        assembler_.AddDepth(m, &ready_);
        Process();
      },
      2);
  if (odometry_.needs_image()) {
    node->Subscribe<image_t>(
        options_.rgb_channel,
        [this](const image_t& m, const common::ReceiveInfo&) {
          assembler_.AddColor(m, &ready_);
          Process();
        },
        4);
  }
  SARMAP_LOG(INFO) << "listening on " << options_.depth_channel
                   << (odometry_.needs_image() ? " + " + options_.rgb_channel : std::string())
                   << ", publishing " << options_.pose_channel << " (method "
                   << options_.odometry.method << ", image scale " << options_.odometry.image_scale
                   << ")";
}

void RgbdOdometryNode::UpdateStatus() {
  const RgbdOdometryStats& s = odometry_.stats();
  std::ostringstream status;
  status.precision(3);
  status << "state " << last_status_name_ << " frames " << s.frames << " tracked " << s.tracked
         << " keyframes " << s.keyframes << " lost " << s.lost << " relocalisations "
         << s.relocalisations << " invalid " << s.invalid << " published " << published_
         << " input_warnings " << assembler_.total_warnings() << " mean_ms "
         << (s.frames > 0 ? total_ms_ / s.frames : 0.0);
  node_->SetStatusMessage(status.str());
}

void RgbdOdometryNode::Process() {
  if (assembler_.total_warnings() != last_warnings_) {
    last_warnings_ = assembler_.total_warnings();
    if (warn_limit_.Allow(common::SteadySeconds())) {
      SARMAP_LOG(WARN) << assembler_.last_warning() << " (" << last_warnings_
                       << " input warnings so far)";
    }
  }
  for (const RgbdFrame& frame : ready_) {
    if (last_utime_ != 0 && frame.utime + 1000000 < last_utime_) {
      SARMAP_LOG(WARN) << "time went back from " << last_utime_ << " to " << frame.utime
                       << " us (a log replayed again?): odometry starts over";
      odometry_.Reset();
      total_ms_ = 0;
    }
    last_utime_ = frame.utime;
    const RgbdOdometryResult r = odometry_.Process(frame);
    if (observer_) observer_(r);
    total_ms_ += r.compute_ms;
    if (r.status != last_status_) {
      const bool bad =
          r.status == TrackingStatus::kLost || r.status == TrackingStatus::kInvalidInput;
      const std::string line = "frame at " + std::to_string(r.utime) +
                               " us: " + TrackingStatusName(r.status) +
                               (r.message.empty() ? "" : ": " + r.message);
      if (!bad) {
        SARMAP_LOG(INFO) << line;
      } else if (warn_limit_.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << line;
      }
      last_status_ = r.status;
      last_status_name_ = TrackingStatusName(r.status);
    }
    if (r.status == TrackingStatus::kInvalidInput) continue;
    if (r.status == TrackingStatus::kLost && !options_.publish_lost) continue;
    pose_t msg{};
    msg.header.utime = r.utime;
    msg.header.frame = options_.frame;
    msg.child_frame = options_.child_frame;
    const Eigen::Quaterniond q(r.world_from_rig.linear());
    common::FromRigid3d(common::Rigid3d(r.world_from_rig.translation(), q), msg.position_m,
                        msg.orientation);
    common::FromCovariance6(PoseCovariance(options_.covariance, r), msg.covariance);
    msg.node_id = -1;
    publisher_.Publish(&msg);
    ++published_;
  }
  ready_.clear();
  UpdateStatus();
}

}  // namespace rgbd_odometry
}  // namespace sarmap
