// SlamNode in-process over memq://: SCAN and ODOM on the bus give a POSE for every scan
// (stamped with it, with a node id), an anchor request is answered with SLAM_ANCHORS, and a
// scan stamped a year ahead is dropped; a changed request over the reply rate is deferred to the
// next optimisation, not dropped.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sarmap/laser_scan_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "slam/slam_node.h"

namespace sarmap {
namespace slam {
namespace {

// The robot at x_m in a square room 6 m wide centred on the start, facing +x: a 181-beam
// half-circle scan of its walls.
laser_scan_t RoomScan(int64_t utime, double x_m) {
  laser_scan_t m{};
  m.header.utime = utime;
  m.header.frame = "base";
  m.angle_min_rad = -M_PI / 2;
  m.angle_increment_rad = M_PI / 180;
  m.range_min_m = 0.1f;
  m.range_max_m = 20.0f;
  for (int i = 0; i <= 180; ++i) {
    const double a = m.angle_min_rad + i * m.angle_increment_rad;
    const double c = std::cos(a), s = std::sin(a);
    double r = 1e9;
    if (c > 1e-9) r = std::min(r, (3.0 - x_m) / c);
    if (c < -1e-9) r = std::min(r, (-3.0 - x_m) / c);
    if (s > 1e-9) r = std::min(r, 3.0 / s);
    if (s < -1e-9) r = std::min(r, -3.0 / s);
    m.ranges_m.push_back(static_cast<float>(r));
  }
  m.num_ranges = static_cast<int32_t>(m.ranges_m.size());
  return m;
}

odometry_t Odometry(int64_t utime, double x_m) {
  odometry_t m{};
  m.header.utime = utime;
  m.header.frame = "odom";
  m.child_frame = "base";
  m.position_m[0] = x_m;
  m.orientation[0] = 1;
  return m;
}

TEST(SlamNodeAdapterTest, ScansAndOdometryOnTheBusGivePosesAndAnchors) {
  common::Node node("slam_node_test", "memq://");
  std::vector<pose_t> poses;
  std::vector<slam_anchors_t> anchors;
  node.Subscribe<pose_t>(
      "POSE", [&](const pose_t& m, const auto&) { poses.push_back(m); }, 100);
  node.Subscribe<slam_anchors_t>(
      "SLAM_ANCHORS", [&](const slam_anchors_t& m, const auto&) { anchors.push_back(m); }, 100);
  SlamNodeOptions options;
  options.map_period_s = 1e9;  // no MAP rendering in this test
  SlamNode adapter(options, &node);
  auto scan_pub = node.Advertise<laser_scan_t>("SCAN");
  auto odom_pub = node.Advertise<odometry_t>("ODOM");
  const auto drain = [&] {
    while (node.lcm().handleTimeout(0) > 0) {
    }
  };
  const int64_t t0 = 1'000'000;
  const int scans = 30;
  for (int i = 0; i < scans; ++i) {
    const int64_t t = t0 + i * 100'000;
    const double x = 0.05 * i;  // 0.5 m/s along x
    auto odom = Odometry(t, x);
    odom_pub.Publish(&odom);
    auto scan = RoomScan(t, x);
    scan_pub.Publish(&scan);
    if (i == scans / 2) {
      auto far = RoomScan(t + 365LL * 86400 * 1'000'000, x);
      scan_pub.Publish(&far);
    }
    drain();
  }
  slam_anchor_request_t request{};
  request.header.utime = t0 + scans * 100'000;
  request.header.frame = "map";
  request.client_id = "sound_map";
  request.node_ids = {0};
  request.num_node_ids = 1;
  node.Advertise<slam_anchor_request_t>("SLAM_ANCHOR_REQUEST").Publish(&request);
  drain();
  adapter.Finish();
  drain();

  EXPECT_EQ(node.stats().at("SCAN").dropped_malformed, 1);
  ASSERT_EQ(poses.size(), static_cast<size_t>(scans));
  for (int i = 0; i < scans; ++i) {
    EXPECT_EQ(poses[i].header.utime, t0 + i * 100'000);
    EXPECT_GE(poses[i].node_id, 0);
    EXPECT_NEAR(poses[i].position_m[0], 0.05 * i, 0.05) << "scan " << i;
  }
  EXPECT_GT(adapter.slam().num_nodes(), 1);
  ASSERT_FALSE(anchors.empty());
  EXPECT_GE(anchors.back().num_anchors, 1);
}

// A client that changes its request faster than its reply rate: the first request is answered at
// once, the second is deferred (no reply yet, not counted as a dropped input) and served by the
// anchors published after the next optimisation.
TEST(SlamNodeAdapterTest, AnchorRequestOverTheReplyRateIsDeferredNotDropped) {
  common::Node node("slam_node_test", "memq://");
  std::vector<slam_anchors_t> anchors;
  node.Subscribe<slam_anchors_t>(
      "SLAM_ANCHORS", [&](const slam_anchors_t& m, const auto&) { anchors.push_back(m); }, 100);
  SlamNodeOptions options;
  options.map_period_s = 1e9;
  options.anchor_replies_per_client_per_min = 6;  // one reply at once, then one every 10 s
  SlamNode adapter(options, &node);
  auto scan_pub = node.Advertise<laser_scan_t>("SCAN");
  auto odom_pub = node.Advertise<odometry_t>("ODOM");
  auto request_pub = node.Advertise<slam_anchor_request_t>("SLAM_ANCHOR_REQUEST");
  const auto drain = [&] {
    while (node.lcm().handleTimeout(0) > 0) {
    }
  };
  const int64_t t0 = 1'000'000;
  for (int i = 0; i < 20; ++i) {
    const int64_t t = t0 + i * 100'000;
    auto odom = Odometry(t, 0.05 * i);
    odom_pub.Publish(&odom);
    auto scan = RoomScan(t, 0.05 * i);
    scan_pub.Publish(&scan);
    drain();
  }
  ASSERT_GT(adapter.slam().num_nodes(), 2);
  slam_anchor_request_t request{};
  request.header.frame = "map";
  request.client_id = "sound_map";
  request.node_ids = {0};
  request.num_node_ids = 1;
  request_pub.Publish(&request);
  drain();
  ASSERT_EQ(anchors.size(), 1u) << "the first request is answered at once";
  request.node_ids = {0, 1};
  request.num_node_ids = 2;
  request_pub.Publish(&request);
  drain();
  EXPECT_EQ(anchors.size(), 1u) << "the changed request is over the reply rate";
  EXPECT_EQ(node.stats().at("SLAM_ANCHOR_REQUEST").dropped_malformed, 0);
  adapter.Finish();
  drain();
  ASSERT_GE(anchors.size(), 2u);
  std::vector<int64_t> ids;
  for (const auto& a : anchors.back().anchors) ids.push_back(a.node_id);
  EXPECT_NE(std::find(ids.begin(), ids.end(), 1), ids.end()) << "the deferred request is served";
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
