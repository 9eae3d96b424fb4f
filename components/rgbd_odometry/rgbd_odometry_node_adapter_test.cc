// RgbdOdometryNode in-process over memq://: synthetic DEPTH + RGB of a rig walking forward in,
// RIG_POSE out (odom -> rig, body convention); time going back a log's length starts over.
#include <gtest/gtest.h>

#include <vector>

#include "rgbd_odometry/frame_messages_test_util.h"
#include "rgbd_odometry/rgbd_odometry_node.h"
#include "rgbd_odometry/synthetic_room.h"

namespace sarmap {
namespace rgbd_odometry {
namespace {

struct Bus {
  common::Node node{"rgbd_odometry_node_test", "memq://"};
  std::vector<pose_t> poses;
  common::Node::Publisher<image_t> depth_pub = node.Advertise<image_t>("DEPTH");
  common::Node::Publisher<image_t> rgb_pub = node.Advertise<image_t>("RGB");
  const synthetic::Room room;
  int64_t seq = 0;
  Bus() {
    node.Subscribe<pose_t>("RIG_POSE",
                           [this](const pose_t& m, const auto&) { poses.push_back(m); });
  }
  // The rig `forward_m` ahead of its start, seen at `utime`.
  void Send(double forward_m, int64_t utime) {
    const Eigen::Isometry3d pose =
        synthetic::Moved(synthetic::StartPose(), {forward_m, 0, 0}, Eigen::Vector3d::UnitZ(), 0);
    testing_util::FrameMessages m = testing_util::FrameMessagesOf(room.Render(pose, utime), seq++);
    rgb_pub.Publish(&m.color);
    depth_pub.Publish(&m.depth);
    for (int i = 0; i < 4; ++i) node.SpinOnce(0.001);
  }
};

TEST(RgbdOdometryNodeTest, WalkingForwardGivesRigPosesAndAReplayStartsOver) {
  Bus bus;
  RgbdOdometryNode adapter(RgbdOdometryNodeOptions(), &bus.node);
  const int64_t t0 = 1700000000000000;
  for (int i = 0; i < 8; ++i) bus.Send(0.01 * i, t0 + i * 33333);
  ASSERT_EQ(bus.poses.size(), 8u);
  EXPECT_EQ(adapter.published(), 8);
  for (size_t i = 0; i < bus.poses.size(); ++i) {
    EXPECT_EQ(bus.poses[i].header.frame, "odom");
    EXPECT_EQ(bus.poses[i].child_frame, "rig");
    EXPECT_NEAR(bus.poses[i].position_m[0], 0.01 * i, 3e-3) << "frame " << i;
  }
  // The log replayed again (time back by more than a second): the odometry starts over, its
  // first frame is the new origin.
  bus.Send(0.05, t0 - 10'000'000);
  ASSERT_EQ(bus.poses.size(), 9u);
  EXPECT_NEAR(bus.poses.back().position_m[0], 0.0, 1e-6);
}

}  // namespace
}  // namespace rgbd_odometry
}  // namespace sarmap
