// sarmap-rgbd-odometry as a process over real LCM (inside a private network namespace):
// synthetic DEPTH + RGB of a rig walking forward in, RIG_POSE out (odom -> rig, body
// convention, growing covariance); undecodable and mismatched images are counted, not fatal;
// SIGINT stops it cleanly.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <lcm/lcm-cpp.hpp>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/node.h"
#include "common/testing/isolated_network.h"
#include "rgbd_odometry/frame_messages_test_util.h"
#include "rgbd_odometry/synthetic_room.h"
#include "sarmap/node_status_t.hpp"
#include "sarmap/pose_t.hpp"
#include "tests/node_watch.h"
#include "tests/process.h"

namespace sarmap {
namespace rgbd_odometry {
namespace {

struct Sink {
  std::vector<pose_t> poses;
  void OnPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* m) {
    poses.push_back(*m);
  }
};

TEST(RgbdOdometryNode, WalkingForwardGivesRigPosesAndBadImagesAreCounted) {
  if (!sarmap::IsolatedNetwork())
    GTEST_SKIP() << "runs through tests/harness/sarmap-netns (ctest does)";
  const std::string src = SARMAP_SOURCE_DIR;
  const std::string log =
      ::testing::TempDir() + "/rgbd_odometry_node_" + std::to_string(getpid()) + ".log";
  testing::Process node({"sarmap-rgbd-odometry", "--config", src + "/config/rgbd_odometry.yaml"},
                        log);
  lcm::LCM lcm(common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  Sink sink;
  lcm.subscribe("RIG_POSE", &Sink::OnPose, &sink);
  testing::NodeStatusSink status("sarmap-rgbd-odometry");
  lcm.subscribe("NODE_STATUS", &testing::NodeStatusSink::OnStatus, &status);
  ASSERT_TRUE(testing::SpinUntil(
      lcm, [&] { return !status.message.empty(); }, 15))
      << node.Output();

  const synthetic::Room room;
  const int64_t t0 = 1700000000000000;
  int64_t seq = 0;
  auto send = [&](int i, bool bad_depth, bool small_color) {
    // 1 cm forward per frame (world x = the rig's forward at the start).
    const Eigen::Isometry3d pose =
        synthetic::Moved(synthetic::StartPose(), {0.01 * i, 0, 0}, Eigen::Vector3d::UnitZ(), 0);
    testing_util::FrameMessages m = testing_util::FrameMessagesOf(
        room.Render(pose, t0 + i * 33333), seq++, small_color ? 320 : 0, small_color ? 240 : 0);
    lcm.publish("RGB", &m.color);
    if (bad_depth) {  // truncated compressed data: consistent sizes, undecodable
      m.depth.data.resize(m.depth.data.size() / 2);
      m.depth.size = static_cast<int32_t>(m.depth.data.size());
    }
    lcm.publish("DEPTH", &m.depth);
  };
  for (int i = 0; i < 8; ++i) {
    send(i, false, false);
    testing::SpinUntil(
        lcm, [&] { return static_cast<int>(sink.poses.size()) > i; }, 10);
  }
  ASSERT_EQ(sink.poses.size(), 8u) << node.Output();
  for (const pose_t& p : sink.poses) {
    EXPECT_EQ(p.header.frame, "odom");
    EXPECT_EQ(p.child_frame, "rig");
    EXPECT_EQ(p.node_id, -1);
  }
  EXPECT_EQ(sink.poses[0].header.utime, t0);
  EXPECT_EQ(sink.poses[0].position_m[0], 0.0);
  const pose_t& last = sink.poses.back();
  EXPECT_EQ(last.header.utime, t0 + 7 * 33333);
  EXPECT_NEAR(last.position_m[0], 0.07, 2e-3);  // forward is +x
  EXPECT_NEAR(last.position_m[1], 0.0, 2e-3);
  EXPECT_NEAR(last.position_m[2], 0.0, 2e-3);
  EXPECT_NEAR(last.orientation[0], 1.0, 1e-4);                 // w: no rotation
  EXPECT_GT(last.covariance[0], sink.poses[0].covariance[0]);  // grows with the path
  EXPECT_GT(last.covariance[35], 0.0);

  // A corrupt depth image and a colour image of the wrong size (both counted by the frame
  // assembler), and a message of the wrong type on DEPTH (dropped by the node runtime): the
  // node carries on from where it was.
  send(8, true, false);
  send(9, false, true);
  const std::vector<uint8_t> junk(100, 0xab);
  lcm.publish("DEPTH", junk.data(), static_cast<unsigned>(junk.size()));
  send(10, false, false);
  ASSERT_TRUE(testing::SpinUntil(
      lcm, [&] { return sink.poses.size() >= 9; }, 10))
      << node.Output();
  EXPECT_NEAR(sink.poses.back().position_m[0], 0.10, 3e-3);
  ASSERT_TRUE(testing::SpinUntil(
      lcm, [&] { return status.InputWarnings().value_or(0) >= 2 && status.dropped >= 1; }, 5))
      << status.message << "; dropped " << status.dropped;
  ASSERT_TRUE(node.Running()) << node.Output();
  node.Signal(SIGINT);
  EXPECT_EQ(node.Wait(10), 0) << node.Output();
  EXPECT_NE(node.Output().find("depth_decode"), std::string::npos) << node.Output();
}

}  // namespace
}  // namespace rgbd_odometry
}  // namespace sarmap
