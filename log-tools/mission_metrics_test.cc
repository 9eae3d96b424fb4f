#include "log-tools/mission_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/compression.h"

namespace sarmap {
namespace logtools {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;  // the first truth, µs
int64_t At(double t_s) { return kT0 + static_cast<int64_t>(std::llround(t_s * 1e6)); }

// The start pose: world_from_map = R(90 deg) p + (10, -2), so a map point (x, y) is the world
// point (10 - y, -2 + x) and a world point (X, Y) is the map point (Y + 2, 10 - X).
constexpr double kStartX = 10, kStartY = -2, kStartYaw = M_PI / 2;
Eigen::Vector2d MapFromWorld(double x, double y) { return {y + 2.0, 10.0 - x}; }

sarmap::sim_truth_t Truth(double x, double y, double yaw, double distance_m, int collisions) {
  sarmap::sim_truth_t t{};
  t.robot_position_m[0] = x;
  t.robot_position_m[1] = y;
  t.robot_orientation[0] = std::cos(yaw / 2);
  t.robot_orientation[3] = std::sin(yaw / 2);
  t.start_pose[0] = kStartX;
  t.start_pose[1] = kStartY;
  t.start_pose[2] = kStartYaw;
  t.distance_m = distance_m;
  t.collisions = collisions;
  const double people[4][2] = {{9.0, -1.0}, {8.0, -2.0}, {10.5, -1.5}, {7.5, -0.75}};  // world
  for (int i = 0; i < 4; ++i) {
    sarmap::sim_person_t p{};
    p.id = 10 + i;
    p.name = std::string(1, static_cast<char>('A' + i));
    p.position_m[0] = people[i][0];
    p.position_m[1] = people[i][1];
    t.people.push_back(p);
  }
  t.num_people = 4;
  return t;
}

// 6 x 4 m of world at 0.25 m from (6, -3); the reachable floor is the 4 x 2 m of x in [7, 11],
// y in [-2.5, -0.5] (16 x 8 cells = 8 m^2), an obstacle footprint beside it.
sarmap::occupancy_grid_t Floor() {
  sarmap::occupancy_grid_t g{};
  g.resolution_m = 0.25;
  g.width = 24;
  g.height = 16;
  g.origin_x_m = 6;
  g.origin_y_m = -3;
  g.data.assign(24 * 16, static_cast<uint8_t>(-1));
  for (int row = 2; row < 10; ++row) {
    for (int col = 4; col < 20; ++col) g.data[row * 24 + col] = 0;
  }
  for (int row = 10; row < 12; ++row) {
    for (int col = 4; col < 20; ++col) g.data[row * 24 + col] = 100;
  }
  g.size = static_cast<int32_t>(g.data.size());
  return g;
}

// SLAM's map: 5 x 6 m at 0.05 m from (-2, -2) in the map frame, known (free, a wall of
// occupied cells) where the map y < known_below_y_m. The reachable floor is map x in
// [-0.5, 1.5], y in [-1, 3]: known below y = 0 covers a quarter of it, below y = 1 a half.
sarmap::occupancy_grid_t Map(double known_below_y_m, bool compress) {
  sarmap::occupancy_grid_t g{};
  g.resolution_m = 0.05;
  g.width = 100;
  g.height = 120;
  g.origin_x_m = -2;
  g.origin_y_m = -2;
  std::vector<uint8_t> cells(100 * 120, static_cast<uint8_t>(-1));
  const int known_rows = static_cast<int>(std::lround((known_below_y_m + 2) / 0.05));
  for (int row = 0; row < known_rows; ++row) {
    for (int col = 0; col < 100; ++col) cells[row * 100 + col] = col == 30 ? 100 : 0;
  }
  if (compress) {
    g.compression = sarmap::occupancy_grid_t::COMPRESSION_ZSTD;
    g.data = common::CompressBytes(cells.data(), cells.size());
  } else {
    g.data = cells;
  }
  g.size = static_cast<int32_t>(g.data.size());
  return g;
}

sarmap::mapped_person_t Mapped(int64_t id, const Eigen::Vector2d& at, int cues) {
  sarmap::mapped_person_t p{};
  p.id = id;
  p.position_m[0] = at.x();
  p.position_m[1] = at.y();
  p.cues = static_cast<int8_t>(cues);
  return p;
}

sarmap::people_map_t People(const std::vector<sarmap::mapped_person_t>& people) {
  sarmap::people_map_t m{};
  m.people = people;
  m.num_people = static_cast<int32_t>(people.size());
  return m;
}

sarmap::explore_status_t Status(const std::string& state) {
  sarmap::explore_status_t s{};
  s.state = state;
  return s;
}

// The robot, facing world +y (yaw 90 deg): still until 12 s, forward 0.2 m/s until 22 s, still
// until 45 s, backward 0.2 m/s until 55 s (back at the start), still until 60 s.
struct Motion {
  double y, distance;
};
Motion RobotAt(double t) {
  if (t <= 12) return {kStartY, 0};
  if (t <= 22) return {kStartY + 0.2 * (t - 12), 0.2 * (t - 12)};
  if (t <= 45) return {kStartY + 2, 2};
  if (t <= 55) return {kStartY + 2 - 0.2 * (t - 45), 2 + 0.2 * (t - 45)};
  return {kStartY, 4};
}

// One mission fed in time order: truth at 10 Hz, inputs interleaved at their times.
MissionMetricsResult RunMission(MissionMetrics* metrics) {
  const int seen = sarmap::mapped_person_t::CUE_SEEN_RGBD,
            heard = sarmap::mapped_person_t::CUE_HEARD;
  const Eigen::Vector2d off(0.3, 0.0);  // within the 0.5 m match radius
  for (int k = 0; k <= 600; ++k) {
    const double t = 0.1 * k;
    if (k == 0) metrics->OnExploreStatus(At(-0.01), Status("exploring"));
    const Motion m = RobotAt(t);
    if (k == 500) metrics->OnExploreStatus(At(t), Status("returning"));
    if (k == 550) metrics->OnExploreStatus(At(t), Status("home"));
    metrics->OnTruth(At(t), Truth(kStartX, m.y, kStartYaw, m.distance, k / 200));
    if (k == 0) metrics->OnFloor(At(0.05), Floor());
    if (k == 10) metrics->OnMap(At(1.0), Map(-2, false));  // nothing known yet: a point
    if (k == 30) metrics->OnMap(At(3.0), Map(0, false));   // 2 s later: not a point
    if (k == 65) metrics->OnMap(At(6.5), Map(0, true));    // a quarter, 5.5 s later: a point
    if (k == 80) metrics->OnMap(At(8.0), Map(1, true));    // 1.5 s later: not a point
    if (k == 590) metrics->OnMap(At(59.0), Map(1, true));  // the last: a point
    if (k == 50) metrics->OnPeopleMap(At(5.0), People({}));
    if (k == 150)
      metrics->OnPeopleMap(At(15.0), People({Mapped(1, MapFromWorld(9.0, -1.0) + off, seen)}));
    if (k == 250) {
      metrics->OnPeopleMap(At(25.0), People({Mapped(1, MapFromWorld(9.0, -1.0) + off, seen),
                                             Mapped(2, MapFromWorld(8.0, -2.0) - off, heard),
                                             Mapped(3, MapFromWorld(10.5, -1.5), seen)}));
    }
    if (k == 580) {
      metrics->OnPeopleMap(At(58.0), People({Mapped(1, MapFromWorld(9.0, -1.0) + off, seen | heard),
                                             Mapped(2, MapFromWorld(8.0, -2.0) - off, heard)}));
    }
  }
  return metrics->Result();
}

TEST(MissionMetricsTest, EveryFigureOfASyntheticMission) {
  MissionMetrics metrics;
  const MissionMetricsResult r = RunMission(&metrics);
  ASSERT_TRUE(r.have_truth);
  EXPECT_NEAR(r.mission_s, 60.0, 1e-9);
  EXPECT_NEAR(r.world_from_map.translation().x(), kStartX, 1e-12);
  EXPECT_NEAR(r.world_from_map.yaw_rad(), kStartYaw, 1e-12);

  // Coverage: the map is where the start pose says; with the identity nothing would be mapped.
  ASSERT_TRUE(r.reachable_m2 && r.mapped_m2 && r.mapped_fraction);
  EXPECT_DOUBLE_EQ(*r.reachable_m2, 8.0);
  EXPECT_DOUBLE_EQ(*r.mapped_m2, 4.0);
  EXPECT_DOUBLE_EQ(*r.mapped_fraction, 0.5);
  ASSERT_EQ(r.coverage.size(), 3u);
  EXPECT_NEAR(r.coverage[0].time_s, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.coverage[0].mapped_m2, 0.0);
  EXPECT_NEAR(r.coverage[1].time_s, 6.5, 1e-9);
  EXPECT_DOUBLE_EQ(r.coverage[1].mapped_m2, 2.0);
  EXPECT_DOUBLE_EQ(r.coverage[1].fraction, 0.25);
  EXPECT_NEAR(r.coverage[2].time_s, 59.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.coverage[2].mapped_m2, 4.0);
  EXPECT_DOUBLE_EQ(r.coverage[2].fraction, 0.5);
  EXPECT_EQ(metrics.UnmappedFloorInMap().size(), 64u);

  // People: A seen at 15 s, B heard at 25 s, C matched at 25 s and gone at the end, D never.
  ASSERT_EQ(r.people.size(), 4u);
  EXPECT_TRUE(r.people[0].found);
  ASSERT_TRUE(r.people[0].found_after_s);
  EXPECT_NEAR(*r.people[0].found_after_s, 15.0, 1e-9);
  const int seen = sarmap::mapped_person_t::CUE_SEEN_RGBD,
            heard = sarmap::mapped_person_t::CUE_HEARD;
  EXPECT_EQ(r.people[0].cues, seen | heard);
  EXPECT_EQ(r.people[0].person_id, 1);
  EXPECT_NEAR(r.people[0].error_m, 0.3, 1e-9);
  EXPECT_TRUE(r.people[1].found);
  ASSERT_TRUE(r.people[1].found_after_s);
  EXPECT_NEAR(*r.people[1].found_after_s, 25.0, 1e-9);
  EXPECT_EQ(r.people[1].cues, heard);
  EXPECT_FALSE(r.people[2].found);
  EXPECT_FALSE(r.people[2].found_after_s);
  EXPECT_TRUE(r.people[2].dropped);
  EXPECT_FALSE(r.people[3].found);
  EXPECT_FALSE(r.people[3].dropped);
  EXPECT_TRUE(r.people[3].map_m.isApprox(MapFromWorld(7.5, -0.75)));

  EXPECT_DOUBLE_EQ(r.distance_m, 4.0);
  EXPECT_EQ(r.collisions, 3);

  // Stuck (10 s window, 0.15 m, 0.2 m/s so 0.14 m in 0.7 s, 0.16 m in 0.8 s): standing from
  // 0 s, stuck from 10.0 s (a full window) until 12.7 s: 2.7 s. Arriving at 22 s: the window
  // from 21.3 s is within 0.14 m of the stop from 31.3 s, until 45.7 s: 14.4 s. Standing at
  // home from 55 s is not judged.
  ASSERT_TRUE(r.stuck_s && r.longest_stuck_s);
  EXPECT_NEAR(*r.stuck_s, 2.7 + 14.4, 1e-9);
  EXPECT_NEAR(*r.longest_stuck_s, 14.4, 1e-9);

  EXPECT_TRUE(r.came_home);
  ASSERT_TRUE(r.home_after_s);
  EXPECT_NEAR(*r.home_after_s, 55.0, 1e-9);
  EXPECT_EQ(r.last_explore_state, "home");
}

TEST(MissionMetricsTest, TurningInPlaceIsNotStuckAndNoStatusIsNotJudged) {
  // Turning at 0.1 rad/s on the spot: 1 rad over the window, never stuck.
  MissionMetrics turning;
  turning.OnExploreStatus(At(0), Status("exploring"));
  MissionMetrics unjudged;
  for (int k = 0; k <= 300; ++k) {
    turning.OnTruth(At(0.1 * k), Truth(kStartX, kStartY, kStartYaw + 0.01 * k, 0, 0));
    unjudged.OnTruth(At(0.1 * k), Truth(kStartX, kStartY, kStartYaw, 0, 0));
  }
  ASSERT_TRUE(turning.Result().stuck_s);
  EXPECT_EQ(*turning.Result().stuck_s, 0.0);
  EXPECT_FALSE(unjudged.Result().stuck_s);
  EXPECT_FALSE(unjudged.Result().longest_stuck_s);
  // Standing still without EXPLORE_STATUS home does not come home.
  EXPECT_FALSE(unjudged.Result().came_home);
  EXPECT_FALSE(unjudged.Result().home_after_s);
}

TEST(MissionMetricsTest, GoingBackAndForthIsGoingNowhereThoughNeverStuck) {
  // Exploring for 200 s: 0-40 s driving straight at 0.2 m/s (8 m), then back and forth over
  // 0.6 m at 0.2 m/s (a robot that backs off, turns and tries the same doorway again) until
  // 150 s, then driving on.
  MissionMetrics metrics;
  metrics.OnExploreStatus(At(0), Status("exploring"));
  double x = kStartX;
  for (int k = 0; k <= 2000; ++k) {
    const double t = 0.1 * k;
    if (t <= 40 || t > 150) {
      x += 0.02;
    } else {
      const double phase = std::fmod(t - 40, 6.0);  // 3 s out, 3 s back
      x += phase < 3 ? 0.02 : -0.02;
    }
    metrics.OnTruth(At(t), Truth(x, kStartY, kStartYaw, 0, 0));
  }
  const MissionMetricsResult r = metrics.Result();
  ASSERT_TRUE(r.longest_stuck_s && r.longest_confined_s);
  EXPECT_EQ(*r.longest_stuck_s, 0.0);  // it always moves more than 0.15 m in 10 s
  // Within 1 m of where it is from ~37 s (the last 0.6 m of the straight drive) to ~152 s.
  EXPECT_NEAR(*r.longest_confined_s, 115.0, 6.0);
}

TEST(MissionMetricsTest, HomeStatusFarFromTheStartIsNotHome) {
  MissionMetrics metrics;
  metrics.OnExploreStatus(At(0), Status("returning"));
  metrics.OnTruth(At(0), Truth(kStartX, kStartY, kStartYaw, 0, 0));
  metrics.OnExploreStatus(At(1), Status("home"));
  metrics.OnTruth(At(1), Truth(kStartX + 0.6, kStartY, kStartYaw, 0.6, 0));
  EXPECT_FALSE(metrics.Result().came_home);
  ASSERT_TRUE(metrics.Result().home_error_m);
  EXPECT_NEAR(*metrics.Result().home_error_m, 0.6, 1e-9);
  metrics.OnTruth(At(2), Truth(kStartX + 0.4, kStartY, kStartYaw, 0.8, 0));
  EXPECT_TRUE(metrics.Result().came_home);
  EXPECT_NEAR(*metrics.Result().home_after_s, 1.0, 1e-9);
}

TEST(MissionMetricsTest, NoFloorNoCoverage) {
  MissionMetrics metrics;
  metrics.OnTruth(At(0), Truth(kStartX, kStartY, kStartYaw, 0, 0));
  metrics.OnMap(At(1), Map(1, false));
  const MissionMetricsResult r = metrics.Result();
  EXPECT_FALSE(r.reachable_m2);
  EXPECT_FALSE(r.mapped_m2);
  EXPECT_TRUE(r.coverage.empty());
  EXPECT_TRUE(metrics.UnmappedFloorInMap().empty());
}

// The trail residual takes the true positions into the map frame by the start pose: a robot
// started at (2, 1) facing +y whose SLAM trail is exact has no residual; a trail 0.3 m short
// in the map's x on half of the samples has sqrt(0.3^2 / 2).
TEST(MissionMetricsTest, TrailResidualAlignsTheTruthByTheStartPose) {
  const common::Rigid2d world_from_map(2.0, 1.0, M_PI / 2);
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d in_map(0.5 * i, 0.2 * i);
    pairs.emplace_back(in_map, world_from_map * in_map);
  }
  EXPECT_NEAR(TrailResidualRms(world_from_map.inverse(), pairs), 0.0, 1e-12);
  // The identity would leave the start pose's offset and turn in.
  EXPECT_GT(TrailResidualRms(common::Rigid2d(), pairs), 1.0);
  pairs[1].first.x() -= 0.3;
  pairs[3].first.x() -= 0.3;
  EXPECT_NEAR(TrailResidualRms(world_from_map.inverse(), pairs), std::sqrt(0.09 / 2), 1e-12);
  EXPECT_EQ(TrailResidualRms(world_from_map.inverse(), {}), 0.0);
}

TEST(MissionMetricsTest, MatchPeopleUsesEachPersonOnceClosestFirst) {
  // One mapped person between two true ones goes to the closer; the other stays unmatched.
  const std::vector<Eigen::Vector2d> truth = {{0, 0}, {0.6, 0}};
  std::vector<double> d;
  const auto match = MatchPeople(truth, {Mapped(7, {0.35, 0}, 0)}, 0.5, &d);
  EXPECT_EQ(match, (std::vector<int>{-1, 0}));
  EXPECT_NEAR(d[1], 0.25, 1e-12);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
