// HandheldSoundMapNode in-process over memq://: a hand-held rig's walk (RIG_POSE and its Kinect
// array's KIND_ANGLE_1D DOAs on the bus) maps the source it passes; a broken pose and DOAs of
// another kind are dropped and counted.
#include <gtest/gtest.h>

#include <vector>

#include "handheld_sound_map/handheld_sound_map_node.h"
#include "handheld_sound_map/handheld_walk_test_util.h"

namespace sarmap {
namespace sound_map {
namespace {

TEST(HandheldSoundMapNodeTest, AWalkPastASourceMapsIt) {
  common::Node node("handheld_sound_map_node_test", "memq://");
  std::vector<sound_map_t> maps;
  node.Subscribe<sound_map_t>("SOUND_MAP",
                              [&](const sound_map_t& m, const auto&) { maps.push_back(m); });
  const auto options = common::LoadOptions<HandheldSoundMapOptions>(
      std::string(SARMAP_SOURCE_DIR) + "/config/handheld_sound_map.yaml", {});
  HandheldSoundMapNode adapter(options, &node);
  auto pose_pub = node.Advertise<pose_t>("RIG_POSE");
  auto doa_pub = node.Advertise<doa_t>("DOA_MAP");
  for (int k = 0; k < testing_util::kWalkSteps; ++k) {
    pose_t pose = testing_util::WalkPose(k);
    if (k == 10) {  // not a unit quaternion: refused by the message checks
      pose_t bad = pose;
      bad.orientation[0] = 3;
      pose_pub.Publish(&bad);
    }
    pose_pub.Publish(&pose);
    doa_t doa = testing_util::WalkDoa(k);
    doa_pub.Publish(&doa);
    while (node.lcm().handleTimeout(0) > 0) {
    }
  }
  adapter.Finish();
  while (node.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(node.stats().at("RIG_POSE").dropped_malformed, 1);
  EXPECT_EQ(adapter.other_kinds(), testing_util::kWalkSteps);
  // Every SOUND_MAP passes the receivers' message checks (no field left uninitialised).
  EXPECT_EQ(node.stats().at("SOUND_MAP").dropped_malformed, 0);
  ASSERT_FALSE(maps.empty());
  const sound_map_t& last = maps.back();
  ASSERT_EQ(last.num_sources, 1);
  const auto& src = last.sources[0];
  const Eigen::Vector3d p(src.position_m[0], src.position_m[1], src.position_m[2]);
  EXPECT_EQ(src.state, +sound_source_t::STATE_CONVERGED);
  EXPECT_TRUE(src.has_position);
  EXPECT_LT((p - testing_util::WalkSource()).norm(), 0.3);
  EXPECT_GE(src.num_observations, 100);
  EXPECT_EQ(last.header.utime, testing_util::WalkDoa(testing_util::kWalkSteps - 1).header.utime);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
