// ExploreNode in-process over memq://: a CMD_VEL for every SCAN, stamped with the scan; an
// emergency stop on TELEOP obeyed; a scan stamped far ahead dropped; odometry with a
// non-finite pose refused; a voice on SOUND_MAP becomes a goal in sound_guided mode.
#include "explore/explore_node.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace sarmap {
namespace explore {
namespace {

// A depth-camera scan of 64 beams over +-30 deg, every beam beyond range (open space).
laser_scan_t OpenScan(int64_t utime) {
  laser_scan_t m{};
  m.header.utime = utime;
  m.header.frame = "base";
  m.angle_min_rad = -M_PI / 6;
  m.angle_increment_rad = (M_PI / 3) / 63;
  m.range_min_m = 0.3f;
  m.range_max_m = 4.0f;
  m.ranges_m.assign(64, std::numeric_limits<float>::infinity());
  m.num_ranges = 64;
  return m;
}

struct Bus {
  common::Node node{"explore_node_test", "memq://"};
  std::vector<velocity_command_t> commands;
  common::Node::Publisher<laser_scan_t> scan_pub = node.Advertise<laser_scan_t>("SCAN");
  Bus() {
    node.Subscribe<velocity_command_t>(
        "CMD_VEL", [this](const velocity_command_t& m, const auto&) { commands.push_back(m); });
  }
  void Drain() {
    while (node.lcm().handleTimeout(0) > 0) {
    }
  }
  void Scan(int64_t utime) {
    auto scan = OpenScan(utime);
    scan_pub.Publish(&scan);
    Drain();
  }
};

TEST(ExploreNodeTest, EveryScanGivesACommandAndAnEmergencyStopIsObeyed) {
  Bus bus;
  ExploreNode adapter(ExploreNodeOptions(), &bus.node);  // no command key: unsigned
  const int64_t t0 = 1'000'000;
  for (int i = 0; i < 5; ++i) bus.Scan(t0 + i * 100'000);
  ASSERT_EQ(bus.commands.size(), 5u);
  for (size_t i = 0; i < bus.commands.size(); ++i) {
    EXPECT_EQ(bus.commands[i].header.utime, t0 + static_cast<int64_t>(i) * 100'000);
    EXPECT_TRUE(std::isfinite(bus.commands[i].linear_mps));
  }
  teleop_t stop{};
  stop.header.utime = 2'000'000;
  stop.header.frame = "base";
  stop.operator_id = "operator";
  stop.emergency_stop = true;
  bus.node.Advertise<teleop_t>("TELEOP").Publish(&stop);
  bus.Drain();
  bus.Scan(t0 + 5 * 100'000);
  ASSERT_EQ(bus.commands.size(), 6u);
  EXPECT_EQ(bus.commands.back().source, "stop");
  EXPECT_EQ(bus.commands.back().linear_mps, 0.0);
  EXPECT_EQ(bus.commands.back().angular_radps, 0.0);
}

TEST(ExploreNodeTest, AScanFarAheadAndANonFiniteOdometryAreRefused) {
  Bus bus;
  ExploreNode adapter(ExploreNodeOptions(), &bus.node);
  bus.Scan(1'000'000);
  bus.Scan(1'000'000 + 365LL * 86400 * 1'000'000);  // a year ahead: no command stamped there
  bus.Scan(1'100'000);
  ASSERT_EQ(bus.commands.size(), 2u);
  EXPECT_EQ(bus.commands.back().header.utime, 1'100'000);
  EXPECT_EQ(bus.node.stats().at("SCAN").dropped_malformed, 1);

  odometry_t odom{};
  odom.header.utime = 1'100'000;
  odom.header.frame = "odom";
  odom.orientation[0] = 1;
  odom.position_m[0] = std::numeric_limits<double>::infinity();  // refused before the controller
  bus.node.Advertise<odometry_t>("ODOM").Publish(&odom);
  bus.Drain();
  EXPECT_EQ(bus.node.stats().at("ODOM").dropped_malformed, 1);
}

// A closed 6 x 4 m room, all known, and the robot at (1, 2) facing +x. A voice on SOUND_MAP at
// (5, 1) that nobody on PEOPLE_MAP explains becomes the goal; once PEOPLE_MAP has someone there
// it is that person and the robot explores instead.
TEST(ExploreNodeTest, AVoiceOnTheSoundMapBecomesAGoal) {
  Bus bus;
  ExploreNodeOptions options;
  options.explore.mode = "sound_guided";
  options.explore.sound.voices = true;
  options.explore.goals.look_around = false;
  options.explore.goals.replan_period_s = 1e-6;  // durations run on the receive clock: replan now
  options.status_period_s = 1e-6;
  ExploreNode adapter(options, &bus.node);
  std::vector<explore_status_t> statuses;
  bus.node.Subscribe<explore_status_t>(
      "EXPLORE_STATUS", [&](const explore_status_t& m, const auto&) { statuses.push_back(m); });

  occupancy_grid_t map{};
  map.header.utime = 1'000'000;
  map.header.frame = "map";
  map.resolution_m = 0.1;
  map.width = 60;
  map.height = 40;
  map.compression = occupancy_grid_t::COMPRESSION_NONE;
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const bool wall = x == 0 || y == 0 || x == map.width - 1 || y == map.height - 1;
      map.data.push_back(wall ? 100 : 0);
    }
  }
  map.size = static_cast<int32_t>(map.data.size());
  bus.node.Advertise<occupancy_grid_t>("MAP").Publish(&map);
  pose_t pose{};
  pose.header.utime = 1'000'000;
  pose.header.frame = "map";
  pose.child_frame = "base";
  pose.position_m[0] = 1.0;
  pose.position_m[1] = 2.0;
  pose.orientation[0] = 1.0;
  pose.node_id = -1;
  bus.node.Advertise<pose_t>("POSE").Publish(&pose);
  sound_map_t sound{};
  sound.header.utime = 1'000'000;
  sound.header.frame = "map";
  sound_source_t voice{};
  voice.id = 4;
  voice.has_position = true;
  voice.position_m[0] = 5.0;
  voice.position_m[1] = 1.0;
  voice.covariance[0] = voice.covariance[4] = voice.covariance[8] = 0.25;
  voice.priority = sound_source_t::PRIORITY_CALL;
  voice.state = sound_source_t::STATE_INITIALISING;
  sound.sources = {voice};
  sound.num_sources = 1;
  bus.node.Advertise<sound_map_t>("SOUND_MAP").Publish(&sound);
  bus.Drain();
  bus.Scan(1'000'000);
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.back().goal_kind, "sound");
  EXPECT_EQ(statuses.back().state, "seeking_sound");

  people_map_t people{};
  people.header.utime = 1'100'000;
  people.header.frame = "map";
  mapped_person_t seen{};
  seen.position_m[0] = 5.0;
  seen.position_m[1] = 1.5;
  seen.cues = mapped_person_t::CUE_SEEN_RGBD;
  people.people = {seen};
  people.num_people = 1;
  bus.node.Advertise<people_map_t>("PEOPLE_MAP").Publish(&people);
  pose.header.utime = 1'100'000;
  bus.node.Advertise<pose_t>("POSE").Publish(&pose);
  bus.Drain();
  bus.Scan(1'100'000);
  EXPECT_NE(statuses.back().goal_kind, "sound");
}

}  // namespace
}  // namespace explore
}  // namespace sarmap
