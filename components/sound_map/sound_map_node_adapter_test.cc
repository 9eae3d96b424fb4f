// SoundMapNode in-process over memq://: a source placed from POSE and DOA on the bus, the anchor
// request it sends, and its stamp gates.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/robot_config.h"
#include "common/testing/pose_messages.h"
#include "sound_map/sound_map_node.h"

namespace sarmap {
namespace sound_map {
namespace {

pose_t Pose(int64_t utime, double x_m, int64_t node_id) {
  pose_t m = common::testing_util::PoseAlongX(utime, x_m);
  m.node_id = node_id;
  return m;
}

doa_t Doa(int64_t utime, double azimuth_rad) {
  doa_t m{};
  m.header.utime = utime;
  m.header.frame = "mic_array";
  m.device_id = "mic";
  doa_source_t s{};
  s.track_id = 1;
  s.kind = doa_source_t::KIND_AZIMUTH;
  s.method = doa_source_t::METHOD_SRP_PHAT;
  s.confidence = 0.9;
  s.azimuth_rad = azimuth_rad;
  s.covariance[0] = s.covariance[3] = std::pow(2 * M_PI / 180, 2);
  m.sources.push_back(s);
  m.num_sources = 1;
  return m;
}

struct Bus {
  common::Node node{"sound_map_node_test", "memq://"};
  std::vector<sound_map_t> maps;
  int requests = 0;
  common::Node::Publisher<pose_t> pose_pub = node.Advertise<pose_t>("POSE");
  common::Node::Publisher<doa_t> doa_pub = node.Advertise<doa_t>("DOA");
  Bus() {
    node.Subscribe<sound_map_t>("SOUND_MAP",
                                [this](const sound_map_t& m, const auto&) { maps.push_back(m); });
    node.Subscribe<slam_anchor_request_t>(
        "SLAM_ANCHOR_REQUEST", [this](const slam_anchor_request_t&, const auto&) { ++requests; });
  }
  void Spin(int times) {
    for (int i = 0; i < times; ++i) node.SpinOnce(0.001);
  }
};

// The robot drives along x at 0.3 m/s for 20 s of message time; a DOA from the array towards
// `source` every 0.1 s. With `far_doa`, one DOA a year ahead goes out halfway.
void DrivePast(Bus* bus, const Eigen::Vector2d& source, bool far_doa) {
  const common::RobotOptions robot = common::LoadRobot(SoundMapNodeOptions().robot_config);
  const Eigen::Vector2d array_on_base(robot.base_from_mic_array.x_m, robot.base_from_mic_array.y_m);
  for (int k = 0; k <= 200; ++k) {
    const int64_t utime = 1'000'000 + k * 100'000;
    const double x = 0.03 * k;
    auto pose = Pose(utime, x, k / 10);
    bus->pose_pub.Publish(&pose);
    const Eigen::Vector2d to_source = source - (Eigen::Vector2d(x, 0) + array_on_base);
    auto doa = Doa(utime + 50'000,
                   std::atan2(to_source.y(), to_source.x()) - robot.base_from_mic_array.yaw_rad);
    bus->doa_pub.Publish(&doa);
    if (far_doa && k == 100) {
      auto far = Doa(utime + 365LL * 86400 * 1'000'000, 0.0);
      bus->doa_pub.Publish(&far);
    }
    bus->Spin(4);
  }
}

TEST(SoundMapNodeTest, PlacesASourceFromTheBusAndRequestsAnchors) {
  Bus bus;
  SoundMapNode adapter(SoundMapNodeOptions(), &bus.node);
  const Eigen::Vector2d source(3.0, 2.0);
  DrivePast(&bus, source, false);
  adapter.Finish();
  bus.Spin(10);
  EXPECT_GE(bus.requests, 1);
  ASSERT_GE(bus.maps.size(), 10u);
  const sound_map_t& last = bus.maps.back();
  ASSERT_EQ(last.num_sources, 1);
  ASSERT_TRUE(last.sources[0].has_position);
  EXPECT_NEAR(last.sources[0].position_m[0], source.x(), 0.3);
  EXPECT_NEAR(last.sources[0].position_m[1], source.y(), 0.3);
  EXPECT_EQ(bus.node.stats().at("DOA").dropped_malformed, 0);
}

TEST(SoundMapNodeTest, ADoaFarAheadIsDroppedAndTheMapGoesOn) {
  Bus bus;
  SoundMapNode adapter(SoundMapNodeOptions(), &bus.node);
  const Eigen::Vector2d source(3.0, 2.0);
  DrivePast(&bus, source, true);
  adapter.Finish();
  bus.Spin(10);
  EXPECT_EQ(bus.node.stats().at("DOA").dropped_malformed, 1);
  ASSERT_FALSE(bus.maps.empty());
  const sound_map_t& last = bus.maps.back();
  ASSERT_EQ(last.num_sources, 1);
  EXPECT_NEAR(last.sources[0].position_m[0], source.x(), 0.3);
  EXPECT_NEAR(last.sources[0].position_m[1], source.y(), 0.3);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
