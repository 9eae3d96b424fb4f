// The covariance the pose graph publishes: each constraint kind's stated noise, not the
// optimiser's tuning weights; and a loop closure weighted per direction by what its match tells.

#include "slam/pose_graph.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace sarmap {
namespace slam {
namespace {

// Submap 0 (fixed) at the origin; node 0 tied to it; nodes 1..n-1 along x, 0.2 m apart, tied
// to their predecessor by local matching.
std::vector<Constraint> Chain(int n, std::vector<Rigid2d>* nodes, std::vector<Rigid2d>* submaps) {
  std::vector<Constraint> constraints;
  submaps->assign(1, Rigid2d(0, 0, 0));
  nodes->clear();
  for (int i = 0; i < n; ++i) nodes->push_back(Rigid2d(0.2 * i, 0, 0));
  constraints.push_back({Constraint::INTRA_SUBMAP, 0, 0, Rigid2d(0, 0, 0), 500, 1600});
  for (int i = 0; i + 1 < n; ++i) {
    constraints.push_back({Constraint::LOCAL_SLAM, i, i + 1, Rigid2d(0.2, 0, 0), 1e5, 1e5});
  }
  return constraints;
}

// In a chain, yaw variances add (rotation is linear) and so do the along-track x variances
// (a heading error does not move a node along its own heading):
//   var(yaw_k) = s_intra_r^2 + k s_local_r^2,   var(x_k) = s_intra_t^2 + k s_local_t^2.
TEST(PoseGraphCovariance, StatedNoisePerKindReplacesTheWeights) {
  std::vector<Rigid2d> nodes, submaps;
  const int n = 11;
  const auto constraints = Chain(n, &nodes, &submaps);
  CovarianceModel model;
  model.intra_submap = {0.05, 1.0 * M_PI / 180};
  model.local_slam = {0.02, 0.3 * M_PI / 180};
  Eigen::MatrixXd cov;
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {0, n - 1}, &cov, PoseGraphOptions(), model));
  ASSERT_EQ(cov.rows(), 6);
  const double k = n - 1;
  const double r_i = M_PI / 180, r_l = 0.3 * M_PI / 180;
  EXPECT_NEAR(cov(5, 5), r_i * r_i + k * r_l * r_l, 1e-9);
  EXPECT_NEAR(cov(3, 3), 0.05 * 0.05 + k * 0.02 * 0.02, 1e-9);
  // The two nodes share the intra-submap error: their cross-covariance is its variance.
  EXPECT_NEAR(cov(2, 5), r_i * r_i, 1e-9);
  // Cross-track: the heading errors swing the last node sideways, so y grows faster than x.
  EXPECT_GT(cov(4, 4), cov(3, 3));
}

TEST(PoseGraphCovariance, ZeroSigmaKeepsTheOptimiserWeights) {
  std::vector<Rigid2d> nodes, submaps;
  const auto constraints = Chain(5, &nodes, &submaps);
  Eigen::MatrixXd cov;
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {4}, &cov, PoseGraphOptions()));
  // Weights are square-root information: 1600 on the intra yaw, 1e5 on each of 4 local yaws.
  EXPECT_NEAR(cov(2, 2), 1.0 / (1600.0 * 1600.0) + 4.0 / 1e10, 1e-12);
  // A model naming only the local-matching rotation leaves every other weight as it was.
  CovarianceModel model;
  model.local_slam.rotation_sigma_rad = 0.01;
  Eigen::MatrixXd cov2;
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {4}, &cov2, PoseGraphOptions(), model));
  EXPECT_NEAR(cov2(2, 2), 1.0 / (1600.0 * 1600.0) + 4.0 * 1e-4, 1e-12);
  EXPECT_NEAR(cov2(0, 0), cov(0, 0), 1e-12);
}

// Trimmed nodes 1..n-2 of the chain: one TRIMMED_CHAIN constraint of n-1 steps between nodes 0
// and n-1 gives the last node the covariance the whole chain gave it (springs in series), and
// the trimmed nodes, in no constraint now, have none.
TEST(PoseGraphCovariance, ATrimmedChainIsTheChainItReplaces) {
  std::vector<Rigid2d> nodes, submaps;
  const int n = 9;
  const auto chain = Chain(n, &nodes, &submaps);
  CovarianceModel model;
  model.intra_submap = {0.05, 1.0 * M_PI / 180};
  model.local_slam = {0.02, 0.3 * M_PI / 180};
  Eigen::MatrixXd whole, trimmed;
  ASSERT_TRUE(NodeCovariance(chain, nodes, submaps, {n - 1}, &whole, PoseGraphOptions(), model));
  Constraint bridge{Constraint::TRIMMED_CHAIN, 0, n - 1, nodes[0].inverse() * nodes[n - 1],
                    1e5 / std::sqrt(n - 1.0), 1e5 / std::sqrt(n - 1.0)};
  bridge.steps = n - 1;
  const std::vector<Constraint> bridged = {chain.front(), bridge};
  ASSERT_TRUE(
      NodeCovariance(bridged, nodes, submaps, {n - 1}, &trimmed, PoseGraphOptions(), model));
  // Along-track x and yaw add linearly in both; the cross-track y of the chain also carries
  // each step's heading error at its lever arm, which one straight constraint does not.
  EXPECT_NEAR(trimmed(0, 0), whole(0, 0), 1e-9);
  EXPECT_NEAR(trimmed(2, 2), whole(2, 2), 1e-12);
  EXPECT_FALSE(NodeCovariance(bridged, nodes, submaps, {3}, &trimmed, PoseGraphOptions(), model));
  // Optimised, the bridge holds the last node where it was.
  std::vector<Rigid2d> moved = nodes;
  moved[n - 1] = Rigid2d(0, 0, 0);
  OptimisePoseGraph(bridged, &moved, &submaps, PoseGraphOptions());
  EXPECT_NEAR((moved[n - 1].translation() - nodes[n - 1].translation()).norm(), 0, 1e-6);
  EXPECT_NEAR(moved[3].translation().x(), 0.6, 1e-12);  // trimmed: left as it was given
}

// A node asked for twice gets the same block everywhere (the anchors may repeat the latest node).
TEST(PoseGraphCovariance, ARepeatedNodeGetsTheSameBlockTwice) {
  std::vector<Rigid2d> nodes, submaps;
  const auto constraints = Chain(5, &nodes, &submaps);
  Eigen::MatrixXd one, twice;
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {4}, &one, PoseGraphOptions()));
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {4, 4}, &twice, PoseGraphOptions()));
  ASSERT_EQ(twice.rows(), 6);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) EXPECT_LT((twice.block<3, 3>(3 * i, 3 * j) - one).norm(), 1e-15);
  }
}

// A node no constraint reaches (trimmed) has no covariance, nor has an unknown node; the others
// keep theirs, the same as without it. A graph in two pieces has none (singular information).
TEST(PoseGraphCovariance, AnUnconstrainedNodeHasNone) {
  std::vector<Rigid2d> nodes, submaps;
  auto constraints = Chain(5, &nodes, &submaps);
  Eigen::MatrixXd without, cov;
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {2}, &without, PoseGraphOptions()));
  nodes.push_back(Rigid2d(3, 0, 0));  // node 5: in the graph, in no constraint
  EXPECT_FALSE(NodeCovariance(constraints, nodes, submaps, {5}, &cov, PoseGraphOptions()));
  EXPECT_FALSE(NodeCovariance(constraints, nodes, submaps, {9}, &cov, PoseGraphOptions()));
  ASSERT_TRUE(NodeCovariance(constraints, nodes, submaps, {2}, &cov, PoseGraphOptions()));
  EXPECT_LT((cov - without).norm(), 1e-15);
  nodes.push_back(Rigid2d(3.2, 0, 0));  // nodes 5 and 6 tied to each other only
  constraints.push_back({Constraint::LOCAL_SLAM, 5, 6, Rigid2d(0.2, 0, 0), 1e5, 1e5});
  EXPECT_FALSE(NodeCovariance(constraints, nodes, submaps, {2}, &cov, PoseGraphOptions()));
}

// A match's translation information, rotated 30 deg: 50 across a wall, 0.001 along it. The shape
// keeps the directions and scales the best one to 1.
TEST(TranslationShapeTest, KeepsTheDirectionsAMatchCanTellWithTheBestAtOne) {
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(M_PI / 6).toRotationMatrix();
  const Eigen::Matrix2d information = r * Eigen::Vector2d(1e-3, 50).asDiagonal() * r.transpose();
  Eigen::Matrix2d shape;
  ASSERT_TRUE(TranslationShape(information, &shape));
  const Eigen::Vector2d along_wall = r.col(0), across_wall = r.col(1);
  EXPECT_NEAR(across_wall.dot(shape * across_wall), 1.0, 1e-12);
  EXPECT_NEAR(along_wall.dot(shape * along_wall), 2e-5, 1e-12);
  EXPECT_NEAR(along_wall.dot(shape * across_wall), 0.0, 1e-12);
  // Well-conditioned information gives nearly the identity; nothing to tell, or NaN: no shape.
  ASSERT_TRUE(TranslationShape(Eigen::Vector2d(40, 50).asDiagonal(), &shape));
  EXPECT_NEAR(shape(0, 0), 0.8, 1e-12);
  EXPECT_NEAR(shape(1, 1), 1.0, 1e-12);
  EXPECT_FALSE(TranslationShape(Eigen::Matrix2d::Zero(), &shape));
  Eigen::Matrix2d nan = Eigen::Matrix2d::Identity();
  nan(0, 1) = std::nan("");
  EXPECT_FALSE(TranslationShape(nan, &shape));
}

// A loop closure whose scan saw one wall along x (it slid 0.5 m along the wall, 0.1 m across it
// is real): with the match's shape it moves the node across the wall only; with the identity
// (one weight for every direction) it drags the node 0.5 m along the wall too.
TEST(PoseGraphShapeTest, ALoopClosureAlongAWallPullsAcrossItNotAlongIt) {
  const auto optimised_last_node = [](const Eigen::Matrix2d& shape) {
    std::vector<Rigid2d> nodes, submaps;
    auto constraints = Chain(6, &nodes, &submaps);
    for (auto& c : constraints) {
      if (c.kind == Constraint::LOCAL_SLAM) c.translation_weight = 1e3;
    }
    Constraint loop{Constraint::LOOP_CLOSURE, 0, 5, Rigid2d(1.0 + 0.5, 0.1, 0), 1.1e4, 1e5};
    loop.translation_shape = shape;
    constraints.push_back(loop);
    PoseGraphOptions options;
    options.huber_scale = 1e9;  // quadratic: the test is about the weights, not the loss
    OptimisePoseGraph(constraints, &nodes, &submaps, options);
    return nodes[5].translation();
  };
  const Eigen::Vector2d plain = optimised_last_node(Eigen::Matrix2d::Identity());
  EXPECT_GT(plain.x() - 1.0, 0.4);
  EXPECT_GT(plain.y(), 0.08);
  Eigen::Matrix2d across_only = Eigen::Matrix2d::Zero();
  across_only(1, 1) = 1.0;
  const Eigen::Vector2d shaped = optimised_last_node(across_only);
  EXPECT_NEAR(shaped.x(), 1.0, 1e-6);
  EXPECT_GT(shaped.y(), 0.08);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
