// A robot with a narrow depth-camera scan drives down a corridor on exact odometry: what local
// matching does to the corridor's length, and MatchablePoints on a small grid.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "slam/scan_matcher.h"
#include "slam/slam.h"

namespace sarmap {
namespace slam {
namespace {

struct Segment {
  Eigen::Vector2d a, b;
};

// A corridor along x from -2 to 24 m, walls at y = +-0.9 m with 1 m doorways, and the rooms'
// far walls at y = +-4 m (beyond a 4.5 m scan through every doorway but at its edge).
std::vector<Segment> Corridor() {
  std::vector<Segment> walls;
  const auto wall_with_doorways = [&walls](double y, const std::vector<double>& doorways_x) {
    double x = -2;
    for (double door_x : doorways_x) {
      walls.push_back({{x, y}, {door_x - 0.5, y}});
      x = door_x + 0.5;
    }
    walls.push_back({{x, y}, {24, y}});
  };
  wall_with_doorways(0.9, {3, 7.5, 12, 16.5});
  wall_with_doorways(-0.9, {5, 10, 14.5});
  walls.push_back({{-2, -4}, {-2, 4}});
  walls.push_back({{24, -4}, {24, 4}});
  walls.push_back({{-2, 4}, {24, 4}});
  walls.push_back({{-2, -4}, {24, -4}});
  return walls;
}

// Distance from `origin` along `angle` to the nearest wall (infinity when none).
double CastRay(const std::vector<Segment>& walls, const Eigen::Vector2d& origin, double angle) {
  const Eigen::Vector2d d(std::cos(angle), std::sin(angle));
  double nearest = INFINITY;
  for (const Segment& s : walls) {
    const Eigen::Vector2d e = s.b - s.a, ao = s.a - origin;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const double t = (ao.x() * e.y() - ao.y() * e.x()) / den;
    const double u = (ao.x() * d.y() - ao.y() * d.x()) / den;
    if (t > 0 && u >= 0 && u <= 1) nearest = std::min(nearest, t);
  }
  return nearest;
}

// Drives 15 m along the corridor's axis at 0.35 m/s: exact odometry at 20 Hz, a 58-degree,
// 320-beam scan at 15 Hz whose returns end at 4.5 m (depth 4.6 m), as the depth camera's.
// Returns SLAM's x minus the true x at the end.
double CorridorLengthError(const SlamOptions& options) {
  Slam slam{options};
  const std::vector<Segment> walls = Corridor();
  const double speed_mps = 0.35, fov_rad = 58 * M_PI / 180;
  const int beams = 320;
  double x_m = 0, next_odometry_s = 0;
  for (int k = 0; x_m < 15; ++k) {
    const double t = k / 15.0;
    x_m = speed_mps * t;
    for (; next_odometry_s <= t; next_odometry_s += 0.05) {
      slam.AddOdometry(next_odometry_s, Rigid2d(speed_mps * next_odometry_s, 0, 0));
    }
    LaserScan scan;
    scan.angle_min_rad = -fov_rad / 2;
    scan.angle_increment_rad = fov_rad / (beams - 1);
    for (int i = 0; i < beams; ++i) {
      const double a = scan.angle_min_rad + i * scan.angle_increment_rad;
      const double r = CastRay(walls, Eigen::Vector2d(x_m, 0), a);
      const bool returns = r <= 4.5 && r * std::cos(a) <= 4.6;
      scan.ranges_m.push_back(returns ? static_cast<float>(r) : 0.f);
    }
    scan.time_s = t;
    scan.range_min_m = 0.45f;
    scan.range_max_m = 4.5f;
    EXPECT_TRUE(slam.AddScan(scan).accepted) << "scan " << k;
  }
  return slam.Trajectory().back().x_m - x_m;
}

TEST(CorridorTest, ANarrowScanKeepsTheCorridorsLengthWhenItMatchesOnlyKnownSpace) {
  // Nothing but the doorways tells the matcher where along the corridor the robot is, and each
  // scan's farthest returns lie beyond what the submap has seen (it is updated at nodes, 0.2 m
  // apart): matched, they pull back at every scan and the corridor comes out short.
  SlamOptions options;  // the matcher's priors of a robot with good odometry (10 / 40)
  options.local.match_known_space_only = false;
  const double all_points_error_m = CorridorLengthError(options);
  options.local.match_known_space_only = true;
  const double known_space_error_m = CorridorLengthError(options);
  std::printf(
      "15 m corridor: SLAM's x error %.3f m matching every point, %.3f m known space only\n",
      all_points_error_m, known_space_error_m);
  EXPECT_LT(all_points_error_m, -0.2);
  EXPECT_LT(std::abs(known_space_error_m), 0.15);  // 1 % of the length
  EXPECT_LT(std::abs(known_space_error_m), std::abs(all_points_error_m) / 3);
}

TEST(CorridorTest, MatchablePointsAreThoseWhereTheGridKnowsTheSpaceAround) {
  // A wall along x at y = 1 (its cells hit), the free space in front of it (y 0..1) seen,
  // nothing behind it; x from 0 to 2 m. Beyond x = 2 m one more column of the wall was hit by
  // a ray that saw nothing around it.
  ProbabilityGrid grid(0.1, Eigen::Vector2d(0, 0));
  RangeData seen;
  seen.origin = Eigen::Vector2f(1, 0);
  for (float x = 0.05f; x < 2.0f; x += 0.1f) seen.hits.emplace_back(x, 1.05f);
  grid.Insert(seen, 0.55f, 0.49f);
  RangeData sliver;
  sliver.origin = Eigen::Vector2f(2.25f, 1.05f);  // a zero-length ray: the hit alone
  sliver.hits.emplace_back(2.25f, 1.05f);
  grid.Insert(sliver, 0.55f, 0.49f);
  ASSERT_NE(grid.Raw(grid.CellIndex(Eigen::Vector2f(2.25f, 1.05f))), 0.f);

  const PointCloud points = {{1.0f, 1.05f},    // on the wall: behind it unknown, in front seen
                             {1.0f, 0.5f},     // in the seen free space
                             {3.0f, 1.05f},    // beyond what the grid has seen
                             {2.25f, 1.05f}};  // the sliver: unknown on its left and right
  const PointCloud kept = MatchablePoints(grid, points, Rigid2d(0, 0, 0));
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept[0], points[0]);
  EXPECT_EQ(kept[1], points[1]);
  // The points are taken at the pose: 2 m further along the wall, the wall point lies beyond
  // what the grid has seen.
  const PointCloud shifted = MatchablePoints(grid, {points[0]}, Rigid2d(2.0, 0, 0));
  EXPECT_TRUE(shifted.empty());
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
