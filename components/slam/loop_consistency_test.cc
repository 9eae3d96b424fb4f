// The loop-closure consistency gate: a closure must agree with the graph within local SLAM's
// drift along the path between its two ends.
#include "slam/loop_consistency.h"

#include <gtest/gtest.h>

#include <cmath>

#include "slam/slam_options.h"

namespace sarmap {
namespace slam {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The gate with the shipped defaults of LoopClosureOptions.
bool Gate(const ChainDrift& chain, int reference, int node, const Rigid2d& predicted,
          const Rigid2d& measured, double* d2) {
  const LoopClosureOptions o;
  return LoopClosureConsistent(chain, reference, node, predicted, measured,
                               o.consistency_match_sigma_m, o.consistency_match_sigma_deg * kDeg,
                               o.consistency_max_chi2, d2);
}

ChainDrift DefaultChain() {
  const LoopClosureOptions o;
  DriftModel m;
  m.translation_m_per_sqrt_m = o.consistency_drift_m_per_sqrt_m;
  m.rotation_rad_per_sqrt_rad = o.consistency_drift_deg_per_sqrt_rad * kDeg;
  m.rotation_rad_per_sqrt_m = o.consistency_drift_deg_per_sqrt_m * kDeg;
  return ChainDrift(m);
}

TEST(LoopConsistencyTest, ATurnOnTheSpotCannotBeHalfAMetreFromItselfALongLoopCan) {
  // A robot turns once on the spot: a node every degree, all at the origin.
  ChainDrift turn = DefaultChain();
  for (int i = 0; i < 360; ++i) turn.Add(Rigid2d(0, 0, i * kDeg));
  // Node 350 matched against the submap that node 10 drew (the submap's frame at the origin).
  const Rigid2d predicted = turn.pose(350);
  double d2_false = 0, d2_true = 0;
  EXPECT_FALSE(Gate(turn, 10, 350, predicted, Rigid2d(0.5, 0.0, 350 * kDeg), &d2_false))
      << "squared Mahalanobis distance " << d2_false;
  // A match within a few centimetres and a degree of where the robot stands agrees.
  EXPECT_TRUE(Gate(turn, 10, 350, predicted, Rigid2d(0.03, -0.02, 351 * kDeg), &d2_true))
      << "squared Mahalanobis distance " << d2_true;
  // The node placed 0.3 m away (the closest of the false closures seen) is rejected too.
  EXPECT_FALSE(Gate(turn, 10, 350, predicted, Rigid2d(0.0, 0.3, 350 * kDeg), nullptr));

  // A 100 m loop (a 25 m square, a node every 0.2 m, corners turned a degree per node) that
  // ends back at the start: after it the same 0.5 m (and 2 degrees) is drift, not a contradiction.
  ChainDrift loop = DefaultChain();
  Eigen::Vector2d p(0, 0);
  double yaw = 0;
  loop.Add(Rigid2d(p, yaw));
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < 125; ++k) {
      p += 0.2 * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
      loop.Add(Rigid2d(p, yaw));
    }
    for (int k = 0; k < 90; ++k) {
      yaw += kDeg;
      loop.Add(Rigid2d(p, yaw));
    }
  }
  const int last = loop.size() - 1;
  ASSERT_LT(loop.pose(last).translation().norm(), 1e-6);
  const Rigid2d back = loop.pose(last);
  EXPECT_TRUE(Gate(loop, 0, last, back, Rigid2d(0.5, 0.0, back.yaw_rad() + 2 * kDeg), &d2_true))
      << "squared Mahalanobis distance " << d2_true;
  // ... but 1 m between two nodes 2 m apart on the first side is still a contradiction.
  EXPECT_FALSE(Gate(loop, 0, 10, loop.pose(10),
                    Rigid2d(loop.pose(10).translation() + Eigen::Vector2d(0, 1.0), 0), nullptr));
  // And the reverse direction (an older node against a later submap) gives the same verdicts.
  EXPECT_TRUE(Gate(loop, last, 0, loop.pose(0), Rigid2d(0.5, 0.0, 2 * kDeg), nullptr));
  EXPECT_FALSE(Gate(turn, 350, 10, turn.pose(10), Rigid2d(0.5, 0.0, 10 * kDeg), nullptr));
}

TEST(LoopConsistencyTest, ReleasingTheNodesBetweenTwoEndsKeepsTheirDriftExact) {
  // A 20 m zig-zag, a node every 0.2 m; nodes 10..89 released (trimmed) as they are added.
  ChainDrift full = DefaultChain(), sparse = DefaultChain();
  for (int i = 0; i < 100; ++i) {
    const Rigid2d pose(0.2 * i, (i / 10) % 2 ? 0.5 : 0.0, 0.01 * i);
    full.Add(pose);
    sparse.Add(pose);
    if (i >= 10 && i < 90) sparse.Release(i);
  }
  EXPECT_EQ(sparse.size(), 100);
  EXPECT_FALSE(sparse.Holds(50));
  EXPECT_TRUE(sparse.Holds(95));
  const Eigen::Matrix3d expected = full.RelativeCovariance(5, 95);
  EXPECT_GT(expected(0, 0), 0.0);
  EXPECT_TRUE(sparse.RelativeCovariance(5, 95).isApprox(expected, 1e-12));
  EXPECT_TRUE(sparse.RelativeCovariance(95, 5).isApprox(full.RelativeCovariance(95, 5), 1e-12));
  EXPECT_LT(sparse.MemoryBytes(), full.MemoryBytes() / 4);
  // A released end bounds nothing: the gate refuses the closure rather than guess.
  EXPECT_TRUE(Gate(full, 50, 95, full.pose(95), full.pose(95), nullptr));
  EXPECT_FALSE(Gate(sparse, 50, 95, sparse.pose(95), sparse.pose(95), nullptr));
}

TEST(LoopConsistencyTest, HeadingDriftSwingsTheFarEndOfALeg) {
  // Turning 180 degrees and then driving 10 m: the heading uncertainty of the turn moves the
  // far end sideways (the lever arm), not along the leg.
  ChainDrift chain = DefaultChain();
  for (int i = 0; i <= 180; ++i) chain.Add(Rigid2d(0, 0, i * kDeg));
  for (int k = 1; k <= 50; ++k) chain.Add(Rigid2d(-0.2 * k, 0, M_PI));
  const Eigen::Matrix3d c = chain.RelativeCovariance(0, chain.size() - 1);
  EXPECT_GT(c(1, 1), 2 * c(0, 0)) << c;
  // Only turning: no position uncertainty at all.
  const Eigen::Matrix3d turn_only = chain.RelativeCovariance(0, 180);
  EXPECT_LT((turn_only.topLeftCorner<2, 2>().norm()), 1e-12) << turn_only;
  EXPECT_GT(turn_only(2, 2), 0);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
