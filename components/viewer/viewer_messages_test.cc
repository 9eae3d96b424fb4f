// What the operator's page shows of each message (viewer_messages.h): cues, classes and states
// by name, values outside their range shown as unknown, bearings, scans in the map frame.
#include "viewer/viewer_messages.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sarmap {
namespace viewer {
namespace {

TEST(ViewerMessagesTest, PeopleShowTheirCues) {
  people_map_t m{};
  mapped_person_t p{};
  p.id = 3;
  p.position_m[0] = 1;
  p.position_m[1] = 2;
  p.covariance[0] = 0.04;  // x std 0.2 m
  p.covariance[4] = 0.01;  // y std 0.1 m
  p.cues = mapped_person_t::CUE_SEEN_DEPTH | mapped_person_t::CUE_HEARD;
  p.people_count = 2;
  p.keyword = "help";
  m.people.push_back(p);
  mapped_person_t colour = p;
  colour.cues = mapped_person_t::CUE_SEEN_RGBD | mapped_person_t::CUE_SEEN_DEPTH;
  m.people.push_back(colour);
  m.num_people = 2;

  const std::vector<PersonView> v = PeopleViews(m);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[0].id, 3);
  EXPECT_TRUE(v[0].seen && v[0].seen_depth_only && v[0].heard);
  EXPECT_EQ(v[0].count, 2);
  EXPECT_EQ(v[0].keyword, "help");
  EXPECT_NEAR(v[0].ellipse.major_m, 3 * 0.2, 1e-9);  // the 3-sigma ellipse
  EXPECT_NEAR(v[0].ellipse.minor_m, 3 * 0.1, 1e-9);
  EXPECT_TRUE(v[1].seen);
  EXPECT_FALSE(v[1].seen_depth_only || v[1].heard);
}

TEST(ViewerMessagesTest, SourcesShowClassStateAndBearing) {
  sound_map_t m{};
  sound_source_t s{};
  s.id = 7;
  s.state = sound_source_t::STATE_CONVERGED;
  s.sound_class = 1;
  s.priority = sound_source_t::PRIORITY_CALL;
  s.has_position = true;
  m.sources.push_back(s);
  sound_source_t bearing = s;
  bearing.state = sound_source_t::STATE_INITIALISING;
  bearing.sound_class = 12;  // out of range
  bearing.priority = sound_source_t::PRIORITY_VOICE;
  bearing.has_position = false;
  bearing.bearing_rad = 0.5;
  bearing.bearing_variance = 0.01;
  m.sources.push_back(bearing);
  sound_source_t silent = s;
  silent.state = sound_source_t::STATE_SILENT;
  silent.sound_class = 3;
  silent.bearing_variance = -1;  // not a variance: no spread
  m.sources.push_back(silent);
  m.num_sources = 3;

  const std::vector<SourceView> v = SourceViews(m);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0].state, "converged");
  EXPECT_EQ(v[0].sound_class, "voice");
  EXPECT_TRUE(v[0].calling);
  EXPECT_EQ(v[1].state, "initialising");
  EXPECT_EQ(v[1].sound_class, "unknown");
  EXPECT_FALSE(v[1].calling);
  EXPECT_FALSE(v[1].has_position);
  EXPECT_DOUBLE_EQ(v[1].bearing_rad, 0.5);
  EXPECT_NEAR(v[1].bearing_sigma_rad, 0.1, 1e-12);
  EXPECT_EQ(v[2].state, "silent");
  EXPECT_EQ(v[2].sound_class, "machinery");
  EXPECT_EQ(v[2].bearing_sigma_rad, 0.0);
}

TEST(ViewerMessagesTest, ProcessesNodesAndTheMission) {
  pm_info_t info{};
  pm_command_status_t c{};
  c.command_id = "slam";
  c.state = pm_command_status_t::STATE_RUNNING;
  c.pid = 42;
  c.restart_count = 1;
  c.rss_bytes = 25'000'000;
  info.commands.push_back(c);
  pm_command_status_t odd = c;
  odd.state = 17;
  info.commands.push_back(odd);
  info.num_commands = 2;
  const std::vector<ProcessView> processes = ProcessViews(info);
  ASSERT_EQ(processes.size(), 2u);
  EXPECT_EQ(processes[0].state, "running");
  EXPECT_EQ(processes[0].pid, 42);
  EXPECT_DOUBLE_EQ(processes[0].rss_mb, 25.0);
  EXPECT_EQ(processes[1].state, "?");

  node_status_t status{};
  status.node_name = "sarmap-slam";
  for (int64_t dropped : {2, 3}) {
    channel_stats_t ch{};
    ch.dropped_malformed = dropped;
    status.channels.push_back(ch);
  }
  status.num_channels = 2;
  const NodeView node = NodeViewOf(status, 12.5);
  EXPECT_EQ(node.name, "sarmap-slam");
  EXPECT_EQ(node.dropped, 5);
  EXPECT_DOUBLE_EQ(node.last_seen_s, 12.5);

  explore_status_t e{};
  e.state = "exploring";
  e.has_goal = true;
  e.goal_m[0] = 3;
  e.path_x_m = {0, 1, 2};
  e.path_y_m = {0, 1};  // one coordinate short: the path stops where both are given
  e.num_path = 2;
  const MissionView mission = MissionViewOf(e);
  EXPECT_EQ(mission.state, "exploring");
  EXPECT_DOUBLE_EQ(mission.goal_x_m, 3);
  ASSERT_EQ(mission.path.size(), 2u);
  EXPECT_EQ(mission.path[1], Eigen::Vector2d(1, 1));
}

TEST(ViewerMessagesTest, ScanReturnsWithinTheirLimitsInTheMapFrame) {
  laser_scan_t scan{};
  scan.angle_min_rad = 0;
  scan.angle_increment_rad = M_PI / 2;
  scan.range_min_m = 0.1f;
  scan.range_max_m = 5.0f;
  scan.ranges_m = {1.0f, std::numeric_limits<float>::quiet_NaN(), 9.0f, 0.05f, 2.0f};
  scan.num_ranges = 5;
  // The robot at (10, 0) facing +y: the beam along its x goes up in the map.
  const std::vector<Eigen::Vector2d> points =
      ScanPointsInMap(scan, common::Rigid2d(10, 0, M_PI / 2));
  ASSERT_EQ(points.size(), 2u);  // NaN, beyond range_max, below range_min dropped
  EXPECT_TRUE(points[0].isApprox(Eigen::Vector2d(10, 1), 1e-12));
  // The fifth beam, at 2 pi: along the robot's x again, 2 m.
  EXPECT_TRUE(points[1].isApprox(Eigen::Vector2d(10, 2), 1e-9));
}

}  // namespace
}  // namespace viewer
}  // namespace sarmap
