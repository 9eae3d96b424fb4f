#include "common/node.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace sarmap {
namespace common {
namespace {

// An anchor request from `client`, numbered `seq` by it, put on the bus as it would arrive.
void Send(Node* node, const std::string& client, int64_t seq) {
  sarmap::slam_anchor_request_t request{};
  request.header.utime = 1;
  request.header.seq = seq;
  request.header.frame = "map";
  request.client_id = client;
  request.node_ids = {seq};
  request.num_node_ids = 1;
  std::vector<uint8_t> bytes(static_cast<size_t>(request.getEncodedSize()));
  request.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  node->lcm().publish("SLAM_ANCHOR_REQUEST", bytes.data(), static_cast<unsigned int>(bytes.size()));
  ASSERT_TRUE(node->SpinOnce(1.0));
}

// SLAM hears anchor requests from the people map and the sound map on one channel, each
// numbering its own: interleaved, nothing is reported lost or late, and a message one client
// loses is counted.
TEST(NodeTest, ChannelsWithSeveralPublishersCountGapsPerPublisher) {
  Node node("node_test", "memq://");
  node.SetStatusChannel("");
  int heard = 0;
  int64_t missed = 0;
  node.Subscribe<sarmap::slam_anchor_request_t>(
      "SLAM_ANCHOR_REQUEST", [&](const sarmap::slam_anchor_request_t&, const ReceiveInfo& info) {
        ++heard;
        missed += info.missed_before;
      });
  for (int64_t seq = 0; seq < 40; ++seq) {
    Send(&node, "people_map", seq);
    if (seq % 4 == 0) Send(&node, "sound_map", seq / 4);
  }
  const ChannelStats& stats = node.stats().at("SLAM_ANCHOR_REQUEST");
  EXPECT_EQ(heard, 50);
  EXPECT_EQ(missed, 0);
  EXPECT_EQ(stats.sequence.gaps(), 0);
  EXPECT_EQ(stats.sequence.reordered(), 0);
  EXPECT_EQ(stats.sequence.publishers(), 2u);

  Send(&node, "sound_map", 12);  // 10 and 11 lost
  Send(&node, "people_map", 40);
  EXPECT_EQ(missed, 2);
  EXPECT_EQ(stats.sequence.gaps(), 2);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
