#pragma once
// Options of sarmap-rgbd-odometry (config/rgbd_odometry.yaml).

#include <string>

#include "common/options.h"
#include "rgbd_odometry/rgbd_odometry.h"

namespace sarmap {
namespace rgbd_odometry {

struct RgbdOdometryNodeOptions {
  RgbdOdometryOptions odometry;
  PoseCovarianceOptions covariance;
  std::string depth_channel = "DEPTH";
  std::string rgb_channel = "RGB";
  std::string pose_channel = "RIG_POSE";
  std::string frame = "odom";       // pose_t header.frame (parent)
  std::string child_frame = "rig";  // pose_t child_frame
  double max_pair_dt_s = 0.02;      // colour within this of the depth's utime
  double color_wait_s = 0.2;        // message time a depth frame waits for its colour
  bool publish_lost = false;        // also publish the held pose of lost frames

  template <class V>
  void Visit(V& v) {
    v("odometry", odometry, "the odometry (rgbd_odometry.h)");
    v("covariance", covariance, "published pose covariance, growing with the path");
    v("depth_channel", depth_channel, "input depth images (image_t)");
    v("rgb_channel", rgb_channel, "input colour images (image_t), used by rgbd and rgbd_icp");
    v("pose_channel", pose_channel, "output rig pose (pose_t)");
    v("frame", frame, "parent frame of the published pose (header.frame)");
    v("child_frame", child_frame, "frame located by the published pose");
    v("max_pair_dt_s", max_pair_dt_s, "colour image paired with depth within this time",
      NonNegative());
    v("color_wait_s", color_wait_s, "message time a depth frame waits for its colour image",
      NonNegative());
    v("publish_lost", publish_lost, "also publish the held pose while tracking is lost");
  }
  void Validate(common::Validator& c) const {
    c.That(!depth_channel.empty(), "depth_channel", "must not be empty");
    c.That(!rgb_channel.empty(), "rgb_channel", "must not be empty");
    c.That(!pose_channel.empty(), "pose_channel", "must not be empty");
    c.That(!frame.empty() && !child_frame.empty(), "frame", "frame names must not be empty");
  }
};

}  // namespace rgbd_odometry
}  // namespace sarmap
