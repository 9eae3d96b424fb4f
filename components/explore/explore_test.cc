#include "explore/explore.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace explore {
namespace {

// A 58-degree scan (Kinect-like), 60 beams, right to left.
Scan MakeScan(double right_m, double left_m) {
  Scan s;
  s.angle_min_rad = -0.5;
  s.angle_increment_rad = 1.0 / 59;
  s.range_min_m = 0.45;
  s.range_max_m = 4.6;
  for (int i = 0; i < 60; ++i) s.ranges_m.push_back(static_cast<float>(i < 30 ? right_m : left_m));
  return s;
}

TEST(ReactiveExplorerTest, ForwardWhenClearTurnsToTheOpenSideWhenClose) {
  ReactiveExplorer r{ReactiveOptions()};
  bool danger = true;
  Velocity v = r.Step(MakeScan(2.0, 2.5), &danger);
  EXPECT_FALSE(danger);
  EXPECT_GT(v.linear_mps, 0);
  EXPECT_EQ(v.angular_radps, 0);

  Scan close = MakeScan(2.0, 3.0);
  close.ranges_m[10] = 0.5f;  // something under 0.6 m on the right
  v = r.Step(close, &danger);
  EXPECT_TRUE(danger);
  EXPECT_EQ(v.linear_mps, 0);
  EXPECT_GT(v.angular_radps, 0);  // left has the larger mean range
  // Keeps turning the same way while in danger even if the right now looks better.
  Scan still = MakeScan(3.2, 2.0);
  still.ranges_m[40] = 0.5f;
  EXPECT_GT(r.Step(still).angular_radps, 0);
}

TEST(ReactiveExplorerTest, TooManyUnknownReadingsAndNarrowPlacesTurnToTheUnknownSide) {
  ReactiveExplorer r{ReactiveOptions()};
  Scan s = MakeScan(0.8, 0.9);  // both means under 1 m
  for (int i = 0; i < 12; ++i) s.ranges_m[i] = NAN;  // 20 % unknown, all on the right
  bool danger = false;
  const Velocity v = r.Step(s, &danger);
  EXPECT_TRUE(danger);
  EXPECT_LT(v.angular_radps, 0);  // towards the right: more unknown, possibly open
  const ScanMetrics m = AnalyseScan(s, ReactiveOptions());
  EXPECT_NEAR(m.unknown_rate, 0.2, 1e-9);
  EXPECT_NEAR(m.unknown_right, 0.4, 1e-9);
}

// A 6 x 4 m room, known only around the robot at the left end; the rest unknown.
Grid PartlyKnownRoom() {
  Grid g;
  g.resolution_m = 0.1;
  g.width = 60;
  g.height = 40;
  g.origin_x_m = 0;
  g.origin_y_m = 0;
  g.cells.assign(g.width * g.height, -1);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < 25; ++x) {
      const bool wall = y == 0 || y == g.height - 1 || x == 0;
      g.cells[y * g.width + x] = wall ? 100 : 0;
    }
  }
  return g;
}

TEST(FrontierExplorerTest, FindsTheFrontierAndDrivesTowardsIt) {
  FrontierExplorer f{FrontierOptions()};
  f.SetMap(PartlyKnownRoom());
  const auto frontiers = f.Frontiers(Eigen::Vector2d(1.0, 2.0));
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_NEAR(frontiers[0].goal_m.x(), 2.45, 0.11);  // the edge of the known part
  EXPECT_GT(frontiers[0].cells.size(), 20u);
  // Facing away from it: turn on the spot; facing it: drive.
  auto away = f.Step(common::Rigid2d(1.0, 2.0, M_PI));
  ASSERT_TRUE(away);
  EXPECT_EQ(away->linear_mps, 0.0);
  EXPECT_NE(away->angular_radps, 0.0);
  auto towards = f.Step(common::Rigid2d(1.0, 2.0, 0.0));
  ASSERT_TRUE(towards);
  EXPECT_GT(towards->linear_mps, 0.1);
  EXPECT_GT(f.path().size(), 5u);
  // Everything known: nothing left to explore.
  Grid done = PartlyKnownRoom();
  for (auto& c : done.cells) c = c < 0 ? 100 : c;
  f.SetMap(done);
  EXPECT_FALSE(f.Step(common::Rigid2d(1.0, 2.0, 0.0)));
}

TEST(ExploreControllerTest, TeleopOverridesUntilTimeoutAndSafetyLayerWins) {
  ExploreController c{ExploreOptions()};
  c.OnMap(PartlyKnownRoom());
  c.OnPose(common::Rigid2d(1.0, 2.0, 0.0));
  TeleopCommand t;
  t.utime = 1'000'000;
  t.override_active = true;
  t.linear_mps = -0.1;
  c.OnTeleop(t);
  EXPECT_EQ(c.OnScan(1'200'000, MakeScan(2, 2)).source, "teleop");
  EXPECT_EQ(c.OnScan(2'000'000, MakeScan(2, 2)).source, "frontier");  // override timed out
  Scan blocked = MakeScan(2, 2);
  blocked.ranges_m[30] = 0.5f;  // valid (above range_min) and under 0.6 m
  EXPECT_EQ(c.OnScan(2'100'000, blocked).source, "reactive");
  t.utime = 3'000'000;
  t.emergency_stop = true;
  c.OnTeleop(t);
  const Velocity v = c.OnScan(9'000'000, MakeScan(2, 2));  // holds after the timeout too
  EXPECT_EQ(v.source, "stop");
  EXPECT_EQ(v.linear_mps, 0);
}

}  // namespace
}  // namespace explore
}  // namespace sarmap
