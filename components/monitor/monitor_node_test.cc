// MonitorNode in-process over memq://: messages counted per channel, a malformed one counted as
// dropped, a bad extra channel refused.
#include "monitor/monitor_node.h"

#include <gtest/gtest.h>

#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace monitor {
namespace {

TEST(MonitorNodeTest, CountsMessagesAndMalformedOnesPerChannel) {
  common::Node node("monitor_node_test", "memq://");
  MonitorOptions options;
  options.print_period_s = 0;
  options.extra_channels = {"POSE_TRUTH=pose_t"};
  MonitorNode adapter(options, &node);
  auto pose = node.Advertise<pose_t>("POSE");
  auto truth = node.Advertise<pose_t>("POSE_TRUTH");
  pose_t m{};
  m.header.frame = "map";
  m.orientation[0] = 1;
  for (int i = 1; i <= 3; ++i) {
    m.header.utime = i * 100000;
    pose.Publish(&m);
    truth.Publish(&m);
  }
  pose_t bad = m;
  bad.position_m[0] = std::nan("");  // refused by the message checks
  pose.Publish(&bad);
  for (int i = 0; i < 20; ++i) node.SpinOnce(0.001);
  adapter.SyncDropped();
  const auto& channels = adapter.monitor().channels();
  ASSERT_EQ(channels.count("POSE"), 1u);
  EXPECT_EQ(channels.at("POSE").total, 3);
  EXPECT_EQ(channels.at("POSE").dropped, 1);
  ASSERT_EQ(channels.count("POSE_TRUTH"), 1u);
  EXPECT_EQ(channels.at("POSE_TRUTH").total, 3);
}

TEST(MonitorNodeTest, AnExtraChannelOfAnUnknownTypeIsAnOptionsError) {
  common::Node node("monitor_node_test", "memq://");
  MonitorOptions options;
  options.extra_channels = {"X=no_such_t"};
  EXPECT_THROW(MonitorNode(options, &node), common::OptionsError);
  options.extra_channels = {"no-equals-sign"};
  EXPECT_THROW(MonitorNode(options, &node), common::OptionsError);
}

}  // namespace
}  // namespace monitor
}  // namespace sarmap
