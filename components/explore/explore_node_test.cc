// ExploreNode in-process over memq://: a CMD_VEL for every SCAN, stamped with the scan; an
// emergency stop on TELEOP obeyed; a scan stamped far ahead dropped; odometry with a
// non-finite pose refused.
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

}  // namespace
}  // namespace explore
}  // namespace sarmap
