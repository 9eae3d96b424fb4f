// Pins the scan matcher maths on a synthetic room: a scan simulated at a known pose, inserted
// into a grid, must be found again from perturbed starting poses by the correlative search,
// the Ceres refinement and the branch-and-bound search.

#include "slam/scan_matcher.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "slam/grid.h"

namespace sarmap {
namespace slam {
namespace {

// Ray-casts a 10 m x 6 m room with a pillar from `pose`, 360 beams.
RangeData SimulateScan(const Rigid2d& pose) {
  RangeData data;
  const int n = 360;
  for (int i = 0; i < n; ++i) {
    const double a = -M_PI + 2 * M_PI * i / n;
    const Eigen::Vector2d dir = pose.rotation() * Eigen::Vector2d(std::cos(a), std::sin(a));
    const Eigen::Vector2d o = pose.translation();
    double best = 1e9;
    // Walls x in [0, 10], y in [0, 6]; pillar [6, 6.6] x [2, 2.6]; an L-shaped inner wall.
    auto seg = [&](Eigen::Vector2d p, Eigen::Vector2d q) {
      const Eigen::Vector2d e = q - p;
      const double den = dir.x() * e.y() - dir.y() * e.x();
      if (std::abs(den) < 1e-12) return;
      const Eigen::Vector2d w = p - o;
      const double t = (w.x() * e.y() - w.y() * e.x()) / den;
      const double u = (w.x() * dir.y() - w.y() * dir.x()) / den;
      if (t > 0 && u >= 0 && u <= 1) best = std::min(best, t);
    };
    const std::vector<Eigen::Vector2d> room = {{0, 0}, {10, 0}, {10, 6}, {0, 6}};
    for (int k = 0; k < 4; ++k) seg(room[k], room[(k + 1) % 4]);
    const std::vector<Eigen::Vector2d> pillar = {{6, 2}, {6.6, 2}, {6.6, 2.6}, {6, 2.6}};
    for (int k = 0; k < 4; ++k) seg(pillar[k], pillar[(k + 1) % 4]);
    seg({2, 4}, {4, 4});
    seg({4, 4}, {4, 5});
    const Eigen::Vector2d local(std::cos(a) * best, std::sin(a) * best);
    data.hits.push_back(local.cast<float>());
  }
  return data;
}

// A branch-and-bound window of +-linear_m and +-angular_rad over a 6-level stack.
BranchAndBoundOptions Window(double linear_m, double angular_rad) {
  BranchAndBoundOptions b;
  b.linear_window_m = linear_m;
  b.angular_window_rad = angular_rad;
  b.depth = 6;
  return b;
}

class ScanMatcherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    grid_ = std::make_unique<ProbabilityGrid>(0.05, Eigen::Vector2d(5.013, 3.011));
    // Map built from a few poses, as local SLAM would.
    for (const Rigid2d& p : {Rigid2d(3, 2, 0.1), Rigid2d(5, 3, -0.4), Rigid2d(7.5, 4.5, 1.0)}) {
      for (int k = 0; k < 30; ++k)
        grid_->Insert(TransformRangeData(SimulateScan(p), p), 0.55f, 0.49f);
    }
    truth_ = Rigid2d(4.2, 2.7, 0.3);
    points_ = VoxelFilter(SimulateScan(truth_).hits, 0.025f);
  }
  std::unique_ptr<ProbabilityGrid> grid_;
  Rigid2d truth_;
  PointCloud points_;
};

TEST_F(ScanMatcherTest, GridStoresHitsAndFreeSpace) {
  // A wall cell is likely occupied, the room centre free, outside unknown.
  EXPECT_GT(grid_->Raw(grid_->CellIndex(Eigen::Vector2f(10.01f, 3.0f))), 0.5f);
  EXPECT_LT(grid_->Raw(grid_->CellIndex(Eigen::Vector2f(5.0f, 1.0f))), 0.5f);
  EXPECT_EQ(grid_->Raw(grid_->CellIndex(Eigen::Vector2f(12.0f, 3.0f))), 0.f);
  // odds update: one hit from 0.5 gives p_hit; a second gives odds^2.
  ProbabilityGrid g(0.1, Eigen::Vector2d::Zero(), 10);
  RangeData d;
  d.hits.push_back(Eigen::Vector2f(0.25f, 0.05f));
  g.Insert(d, 0.55f, 0.49f);
  EXPECT_NEAR(g.Raw(g.CellIndex(d.hits[0])), 0.55f, 1e-6);
  g.Insert(d, 0.55f, 0.49f);
  const double odds = (0.55 / 0.45) * (0.55 / 0.45);
  EXPECT_NEAR(g.Raw(g.CellIndex(d.hits[0])), odds / (1 + odds), 1e-6);
  // The ray from the origin passes (0.05, 0.05) .. (0.15, 0.05): two misses.
  const double miss_odds = (0.49 / 0.51) * (0.49 / 0.51);
  EXPECT_NEAR(g.Raw(g.CellIndex(Eigen::Vector2f(0.15f, 0.05f))), miss_odds / (1 + miss_odds), 1e-6);
}

TEST(ProbabilityGridTest, RaysClearOnlyFromTheGivenRangeOn) {
  // A low object at 0.8 m, seen from 3 m, then passed over by rays from 0.5 m away (a depth
  // camera from close by): clearing from 1.2 m on keeps it; clearing all along erases it.
  for (const float free_from_m : {0.f, 1.2f}) {
    ProbabilityGrid g(0.1, Eigen::Vector2d::Zero(), 10);
    RangeData far;
    far.origin = Eigen::Vector2f(-2.15f, 0.05f);
    far.hits.push_back(Eigen::Vector2f(0.85f, 0.05f));
    g.Insert(far, 0.55f, 0.49f, free_from_m);
    RangeData close;
    close.origin = Eigen::Vector2f(0.35f, 0.05f);
    close.hits.push_back(Eigen::Vector2f(3.05f, 0.05f));  // the wall behind it
    for (int i = 0; i < 10; ++i) g.Insert(close, 0.55f, 0.49f, free_from_m);
    const float object = g.Raw(g.CellIndex(Eigen::Vector2f(0.85f, 0.05f)));
    if (free_from_m > 0) {
      EXPECT_NEAR(object, 0.55f, 1e-6);
      // Each ray clears from 1.2 m off its origin on: the close rays at (2.05, 0), 1.7 m away;
      // the far one at (-0.55, 0), 1.6 m away, but not at (-1.55, 0), 0.6 m away.
      EXPECT_LT(g.Raw(g.CellIndex(Eigen::Vector2f(2.05f, 0.05f))), 0.5f);
      EXPECT_EQ(g.Raw(g.CellIndex(Eigen::Vector2f(-1.55f, 0.05f))), 0.f);
      EXPECT_LT(g.Raw(g.CellIndex(Eigen::Vector2f(-0.55f, 0.05f))), 0.5f);
    } else {
      EXPECT_LT(object, 0.5f);
    }
  }
}

TEST_F(ScanMatcherTest, AngularStepMovesFarthestPointByOneCell) {
  PointCloud p = {Eigen::Vector2f(10, 0)};
  const double step = AngularSearchStep(p, 0.05);
  // chord of the farthest point = resolution
  EXPECT_NEAR(2 * 10 * std::sin(step / 2), 0.05, 1e-6);
}

TEST_F(ScanMatcherTest, CorrelativeThenCeresRecoversPose) {
  const Rigid2d start(truth_.translation() + Eigen::Vector2d(0.07, -0.06), truth_.yaw_rad() + 0.12);
  CorrelativeOptions c;
  c.linear_window_m = 0.15;
  c.angular_window_rad = 0.25;
  double score = 0;
  const Rigid2d coarse = CorrelativeMatch(*grid_, points_, start, c, &score);
  EXPECT_LT((coarse.translation() - truth_.translation()).norm(), 0.05);
  EXPECT_LT(std::abs(coarse.yaw_rad() - truth_.yaw_rad()), 0.02);
  EXPECT_GT(score, 0.55);
  CeresMatcherOptions m;
  const Rigid2d fine = CeresMatch(*grid_, points_, coarse, coarse, m);
  // Sub-cell accuracy (cells are 0.05 m; hit cells quantise the walls).
  EXPECT_LT((fine.translation() - truth_.translation()).norm(), 0.03);
  EXPECT_LT(std::abs(fine.yaw_rad() - truth_.yaw_rad()), 0.01);
  EXPECT_GE(ScoreAt(*grid_, points_, fine), ScoreAt(*grid_, points_, start));
}

TEST_F(ScanMatcherTest, BranchAndBoundFindsPoseInLargeWindow) {
  const Rigid2d start(truth_.translation() + Eigen::Vector2d(-1.3, 0.8), truth_.yaw_rad() - 0.3);
  PrecomputationStack stack(*grid_, 6);
  // Upper bound property: level h value >= every level-0 value in its window.
  for (int y = -3; y < 20; y += 3) {
    for (int x = -3; x < 20; x += 3) {
      int m = 0;
      for (int dy = 0; dy < 8; ++dy)
        for (int dx = 0; dx < 8; ++dx) m = std::max(m, stack.Value(0, x + dx, y + dy));
      EXPECT_EQ(stack.Value(3, x, y), m);
    }
  }
  const BranchAndBoundOptions b = Window(2.0, 0.5);
  Rigid2d found;
  double score = 0;
  ASSERT_TRUE(BranchAndBoundMatch(*grid_, stack, points_, start, b, 0.5, &found, &score));
  EXPECT_LT((found.translation() - truth_.translation()).norm(), 0.08);
  EXPECT_LT(std::abs(found.yaw_rad() - truth_.yaw_rad()), 0.02);
  // The exact score of the found pose equals the reported one (leaf level is exact).
  EXPECT_NEAR(ScoreAt(*grid_, points_, found), score, 0.02);
  // Nothing reaches an impossible score.
  EXPECT_FALSE(BranchAndBoundMatch(*grid_, stack, points_, start, b, 0.95, &found, &score));
}

TEST_F(ScanMatcherTest, BranchAndBoundScoreIsTheExhaustiveSearchsBest) {
  // A 2 m window around a scan that spans the room: most candidates put some points outside
  // the stack (scored point by point), the rest lie inside (children scored in groups of four).
  // Either way the search returns the best of every candidate scored one by one, and the
  // candidate it returns has that score.
  PrecomputationStack stack(*grid_, 5);
  const BranchAndBoundOptions b = Window(2.0, 0.1);
  const double res = grid_->resolution();
  const double step = AngularSearchStep(points_, res, b.step_range_cap_m);
  const int num_angles = static_cast<int>(std::ceil(b.angular_window_rad / step));
  const int w = static_cast<int>(std::ceil(b.linear_window_m / res));
  const double n = static_cast<double>(points_.size());
  const auto probability = [&](int64_t sum) {
    return kMinProbability +
           (kMaxProbability - kMinProbability) * static_cast<double>(sum) / (255.0 * n);
  };
  int partly_outside = 0, inside = 0;
  for (const Eigen::Vector3d& offset :
       {Eigen::Vector3d(0.6, -0.4, 0.05), Eigen::Vector3d(-0.35, 0.25, -0.08),
        Eigen::Vector3d(0.05, 0.9, 0.02), Eigen::Vector3d(-1.1, -0.2, 0.0)}) {
    const Rigid2d start(truth_.translation() + offset.head<2>(), truth_.yaw_rad() + offset.z());
    Rigid2d found;
    double score = 0;
    ASSERT_TRUE(BranchAndBoundMatch(*grid_, stack, points_, start, b, 0.0, &found, &score));
    const int found_k = static_cast<int>(std::lround((found.yaw_rad() - start.yaw_rad()) / step));
    const Eigen::Vector2d found_cells = (found.translation() - start.translation()) / res;
    int64_t best = -1, found_sum = -1;
    for (int k = -num_angles; k <= num_angles; ++k) {
      const Eigen::Matrix2f r =
          Eigen::Rotation2Df(static_cast<float>(start.yaw_rad() + k * step)).toRotationMatrix();
      const Eigen::Vector2f t = start.translation().cast<float>();
      std::vector<Eigen::Array2i> cells;
      for (const auto& p : points_) cells.push_back(grid_->CellIndex(r * p + t));
      for (int dy = -w; dy <= w; ++dy) {
        for (int dx = -w; dx <= w; ++dx) {
          int64_t sum = 0;
          bool all_inside = true;
          for (const auto& c : cells) {
            sum += stack.Value(0, c.x() + dx, c.y() + dy);
            all_inside = all_inside && stack.Contains(c.x() + dx, c.y() + dy);
          }
          ++(all_inside ? inside : partly_outside);
          best = std::max(best, sum);
          if (k == found_k && dx == std::lround(found_cells.x()) &&
              dy == std::lround(found_cells.y())) {
            found_sum = sum;
          }
        }
      }
    }
    EXPECT_DOUBLE_EQ(score, probability(best));
    EXPECT_DOUBLE_EQ(score, probability(found_sum));
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(partly_outside, 1000);
}

TEST_F(ScanMatcherTest, AMatchOutsideTheWindowEndsOnItsBoundary) {
  PrecomputationStack stack(*grid_, 6);
  const BranchAndBoundOptions b = Window(0.5, 0.2);
  Rigid2d found;
  double score = 0;
  // The truth inside the window: an interior maximum.
  const Rigid2d near(truth_.translation() + Eigen::Vector2d(0.2, -0.1), truth_.yaw_rad() + 0.05);
  ASSERT_TRUE(BranchAndBoundMatch(*grid_, stack, points_, near, b, 0.3, &found, &score));
  EXPECT_LT((found.translation() - truth_.translation()).norm(), 0.08);
  EXPECT_FALSE(OnWindowBoundary(*grid_, points_, near, b, found));
  // The truth 0.9 m away along x: the best the window holds lies on its edge.
  const Rigid2d far(truth_.translation() + Eigen::Vector2d(-0.9, 0.0), truth_.yaw_rad());
  ASSERT_TRUE(BranchAndBoundMatch(*grid_, stack, points_, far, b, 0.0, &found, &score));
  EXPECT_TRUE(OnWindowBoundary(*grid_, points_, far, b, found));
  // So is a pose at the outermost angle.
  const double step = AngularSearchStep(points_, grid_->resolution(), b.step_range_cap_m);
  const Rigid2d turned(near.translation(),
                       near.yaw_rad() + std::ceil(b.angular_window_rad / step) * step);
  EXPECT_TRUE(OnWindowBoundary(*grid_, points_, near, b, turned));
  EXPECT_FALSE(OnWindowBoundary(*grid_, points_, near, b, near));
}

TEST_F(ScanMatcherTest, AFinishedGridIsCroppedToSixteenBitsAndMatchesAsBefore) {
  // The 16-bit code: every code decodes and encodes back to itself, every probability to
  // within half a step.
  const float half_step = 0.5f * (kMaxProbability - kMinProbability) / 32766.f;
  EXPECT_EQ(ProbabilityGrid::Encode(0.f), 0);
  EXPECT_EQ(ProbabilityGrid::Decode(0), 0.f);
  for (int v = 1; v <= 32767; ++v) {
    ASSERT_EQ(ProbabilityGrid::Encode(ProbabilityGrid::Decode(static_cast<uint16_t>(v))), v);
  }
  EXPECT_EQ(ProbabilityGrid::Decode(1), kMinProbability);
  EXPECT_NEAR(ProbabilityGrid::Decode(32767), kMaxProbability, 1e-6);
  for (float p = kMinProbability; p <= kMaxProbability; p += 0.000713f) {
    ASSERT_NEAR(ProbabilityGrid::Decode(ProbabilityGrid::Encode(p)), p, half_step + 1e-7f) << p;
  }
  ProbabilityGrid finished = *grid_;
  finished.Finish();
  EXPECT_TRUE(finished.finished());
  EXPECT_EQ(finished.LiveCells(), nullptr);
  // Growth leaves unknown margins: the finished grid holds only the known cells, two bytes each.
  EXPECT_LT(static_cast<int64_t>(finished.width()) * finished.height(),
            static_cast<int64_t>(grid_->width()) * grid_->height());
  EXPECT_EQ(finished.MemoryBytes(),
            static_cast<size_t>(finished.width()) * finished.height() * sizeof(uint16_t));
  for (float y = -2.f; y < 9.f; y += 0.07f) {
    for (float x = -2.f; x < 13.f; x += 0.07f) {
      const Eigen::Vector2f p(x, y);
      const float before = grid_->Raw(grid_->CellIndex(p));
      const float after = finished.Raw(finished.CellIndex(p));
      ASSERT_EQ(after == 0.f, before == 0.f) << x << " " << y;
      ASSERT_NEAR(after, before, half_step + 1e-7f) << x << " " << y;
    }
  }
  // The matchers give the same poses and scores on both.
  const Rigid2d start(truth_.translation() + Eigen::Vector2d(0.07, -0.06), truth_.yaw_rad() + 0.12);
  CorrelativeOptions c;
  c.linear_window_m = 0.15;
  c.angular_window_rad = 0.25;
  double score_before = 0, score_after = 0;
  const Rigid2d before = CorrelativeMatch(*grid_, points_, start, c, &score_before);
  const Rigid2d after = CorrelativeMatch(finished, points_, start, c, &score_after);
  EXPECT_NEAR((before.translation() - after.translation()).norm(), 0, 1e-9);
  EXPECT_NEAR(before.yaw_rad(), after.yaw_rad(), 1e-12);
  EXPECT_NEAR(score_before, score_after, 1e-4);
  const BranchAndBoundOptions b = Window(2.0, 0.5);
  Rigid2d found_before, found_after;
  ASSERT_TRUE(BranchAndBoundMatch(*grid_, PrecomputationStack(*grid_, 6), points_, start, b, 0.5,
                                  &found_before, &score_before));
  ASSERT_TRUE(BranchAndBoundMatch(finished, PrecomputationStack(finished, 6), points_, start, b,
                                  0.5, &found_after, &score_after));
  EXPECT_NEAR((found_before.translation() - found_after.translation()).norm(), 0, 1e-9);
  EXPECT_NEAR(score_before, score_after, 1e-3);
  // A finished grid can still take a scan (back in floats).
  finished.Insert(TransformRangeData(SimulateScan(truth_), truth_), 0.55f, 0.49f);
  EXPECT_FALSE(finished.finished());
  EXPECT_GT(finished.Raw(finished.CellIndex(Eigen::Vector2f(10.01f, 3.0f))), 0.5f);
}

TEST_F(ScanMatcherTest, RotationInformationIsWhatTurningTellsBeyondSliding) {
  // The whole room (corners, a pillar) pins the heading.
  const double room = RotationInformation(*grid_, points_, truth_, 1.0, 10.0);
  EXPECT_GT(room, 100.0);
  // Freeing the translation can only lose heading information (Schur complement): with the
  // translation held fixed by a huge prior it is the plain H_theta_theta.
  const double held = RotationInformation(*grid_, points_, truth_, 1.0, 1e6);
  const double free = RotationInformation(*grid_, points_, truth_, 1.0, 0.0);
  EXPECT_GE(held, room);
  EXPECT_GE(room, free);
  // The same points seen in a narrow, distant sector (a depth camera looking down a room):
  // turning the scan looks like sliding it sideways, little heading information is left.
  PointCloud sector;
  for (const auto& p : points_) {
    if (p.norm() > 3.0f && std::abs(std::atan2(p.y(), p.x())) < 0.15f) sector.push_back(p);
  }
  ASSERT_GE(sector.size(), 5u);
  EXPECT_LT(RotationInformation(*grid_, sector, truth_, 1.0, 0.0), 0.2 * free);
  EXPECT_EQ(RotationInformation(*grid_, PointCloud(), truth_, 1.0, 10.0), 0.0);
}

// A corridor 2 m wide along x (walls y = 0 and y = 2, x in [0, 20]) seen by a depth camera:
// 57 deg, returns up to 4.5 m, 120 beams, from `pose`.
RangeData SimulateCorridorScan(const Rigid2d& pose) {
  RangeData data;
  const int n = 120;
  const double fov = 57 * M_PI / 180;
  for (int i = 0; i < n; ++i) {
    const double a = -fov / 2 + fov * i / (n - 1);
    const double heading = pose.yaw_rad() + a;
    const double dy = std::sin(heading);
    if (std::abs(dy) < 1e-9) continue;
    const double wall_y = dy > 0 ? 2.0 : 0.0;
    const double range = (wall_y - pose.translation().y()) / dy;
    const double x = pose.translation().x() + range * std::cos(heading);
    if (range > 4.5 || x < 0 || x > 20) continue;
    data.hits.push_back(Eigen::Vector2f(std::cos(a) * range, std::sin(a) * range));
  }
  return data;
}

// The grid of a robot that drove down the corridor from x = 1 to x = `to_x`.
std::unique_ptr<ProbabilityGrid> CorridorGrid(double to_x) {
  auto grid = std::make_unique<ProbabilityGrid>(0.05, Eigen::Vector2d(5.013, 1.011));
  for (double x = 1.0; x <= to_x + 1e-9; x += 0.05) {
    const Rigid2d p(x, 1.0, 0.0);
    grid->Insert(TransformRangeData(SimulateCorridorScan(p), p), 0.55f, 0.49f);
  }
  return grid;
}

TEST_F(ScanMatcherTest, AMatchInACorridorCannotTellAlongItsAxis) {
  const auto corridor = CorridorGrid(8.0);
  const Rigid2d pose(5.0, 1.0, 0.0);
  const PointCloud points = VoxelFilter(SimulateCorridorScan(pose).hits, 0.025f);
  ASSERT_GE(points.size(), 50u);
  const Eigen::Matrix3d h = MapTermHessian(*corridor, points, pose, 1.0);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> corridor_eigen(h.topLeftCorner<2, 2>());
  // The weakest direction is the corridor's axis, and it tells almost nothing.
  EXPECT_GT(std::abs(corridor_eigen.eigenvectors()(0, 0)), 0.95);
  EXPECT_LT(corridor_eigen.eigenvalues()(0), 0.02 * corridor_eigen.eigenvalues()(1));
  // The room (corners, a pillar, 360 deg) tells both directions.
  const Eigen::Matrix3d room = MapTermHessian(*grid_, points_, truth_, 1.0);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> room_eigen(room.topLeftCorner<2, 2>());
  EXPECT_GT(room_eigen.eigenvalues()(0), 0.2 * room_eigen.eigenvalues()(1));
  // The Hessian is the one RotationInformation uses: its Schur complement on theta.
  const Eigen::Matrix2d h_xx = h.topLeftCorner<2, 2>();
  const Eigen::Vector2d h_xt = h.topRightCorner<2, 1>();
  EXPECT_NEAR(RotationInformation(*corridor, points, pose, 1.0, 0.0),
              std::max(0.0, h(2, 2) - h_xt.dot(h_xx.ldlt().solve(h_xt))), 1e-6 * h(2, 2));
  EXPECT_TRUE(MapTermHessian(*corridor, PointCloud(), pose, 1.0).isZero());
}

TEST(AdaptiveRotationWeightTest, BaseBelowLowInformativeAboveHighLogLinearBetween) {
  EXPECT_DOUBLE_EQ(AdaptiveRotationWeight(500, 40, 10, 1e3, 1e4), 40);
  EXPECT_DOUBLE_EQ(AdaptiveRotationWeight(2e4, 40, 10, 1e3, 1e4), 10);
  // Geometric middle of the information range: geometric middle of the weights.
  EXPECT_NEAR(AdaptiveRotationWeight(std::sqrt(1e7), 40, 10, 1e3, 1e4), 20, 1e-9);
  // Off: the base weight whatever the information.
  EXPECT_DOUBLE_EQ(AdaptiveRotationWeight(2e4, 40, 0, 1e3, 1e4), 40);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
