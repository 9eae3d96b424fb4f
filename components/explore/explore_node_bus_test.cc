// ExploreNode in-process over real UDP multicast (in the private network namespace ctest runs
// it in): LCM's receive thread queues each subscription's messages up to its capacity, so
// this is where a latest-only subscription would pass messages over. Poses and odometry that
// arrive while the node is busy are all handled: each one extends the trail or the odometry
// history, and NODE_STATUS counts no gap.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "common/testing/isolated_network.h"
#include "common/testing/pose_messages.h"
#include "explore/explore_node.h"

namespace sarmap {
namespace explore {
namespace {

TEST(ExploreNodeBusTest, PosesAndOdometryArrivingWhileBusyAreAllHandled) {
  if (!IsolatedNetwork()) GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
  common::Node node("explore_node_bus_test", "udpm://239.255.76.67:7667?ttl=0");
  ExploreNode adapter(ExploreNodeOptions(), &node);
  auto pose_pub = node.Advertise<pose_t>("POSE");
  auto odom_pub = node.Advertise<odometry_t>("ODOM");
  constexpr int kEach = 20;
  for (int i = 0; i < kEach; ++i) {
    pose_t pose = common::testing_util::PoseAlongX(1'000'000 + i * 33'000, 0.01 * i);
    pose_pub.Publish(&pose);
    odometry_t odom{};
    odom.header.utime = pose.header.utime;
    odom.header.frame = "odom";
    odom.child_frame = "base";
    odom.position_m[0] = 0.01 * i;
    odom.orientation[0] = 1;
    odom_pub.Publish(&odom);
  }
  // The node is busy: nothing is handled until every message is in LCM's queues.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  while (node.lcm().handleTimeout(50) > 0) {
  }
  for (const char* channel : {"POSE", "ODOM"}) {
    ASSERT_EQ(node.stats().count(channel), 1u) << channel << " never handled";
    const common::ChannelStats& stats = node.stats().at(channel);
    EXPECT_EQ(stats.received, kEach) << channel;
    EXPECT_EQ(stats.sequence.gaps(), 0) << channel;
  }
}

}  // namespace
}  // namespace explore
}  // namespace sarmap
