#include "sound_map/idp_ekf.h"

#include <gtest/gtest.h>

#include <random>

#include "sound_map/experiments.h"
#include "sound_map/joint_optimizer.h"

namespace sarmap {
namespace sound_map {
namespace {

// A source seen from two poses with exact bearings: the IDP EKF with a tiny bearing noise
// triangulates it.
TEST(IdpEkf, TriangulatesFromParallax2d) {
  IdpEkf::Options o;
  IdpEkf ekf(o);
  ekf.Reset(Pose2(0, 0, 0), Eigen::Matrix3d::Zero());
  const Eigen::Vector3d src(3.0, 2.0, 0.0);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(1, 1) * 1e-6;
  for (int k = 0; k < 30; ++k) {
    if (k > 0) ekf.Predict(Pose2(0.1, 0, 0), Eigen::Matrix3d::Zero());
    const Pose2 x = ekf.current();
    const double pose[3] = {x.x, x.y, x.yaw};
    double z[2];
    PointObservation(pose, src.data(), false, o.mount, z);
    Eigen::VectorXd zv(1);
    zv << z[0];
    if (!ekf.HasSource(7)) ekf.AddSource(7, k, zv, r); else ekf.UpdateSource(7, zv, r);
  }
  Eigen::Vector3d p;
  Eigen::Matrix3d c;
  ekf.SourcePoint(7, &p, &c);
  EXPECT_NEAR(p.x(), 3.0, 0.02);
  EXPECT_NEAR(p.y(), 2.0, 0.02);
}

// Removing a source keeps the others exactly (mean and covariance); an anchor is removed
// only once no source uses it.
TEST(IdpEkf, RemovesSourcesAndUnusedAnchors) {
  IdpEkf ekf(IdpEkf::Options{});
  ekf.Reset(Pose2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-4);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(1, 1) * 1e-3;
  Eigen::VectorXd z(1);
  z << 0.3;
  ekf.AddSource(1, 10, z, r);
  ekf.Predict(Pose2(0.5, 0, 0.1), Eigen::Matrix3d::Identity() * 1e-4);
  z << -0.4;
  ekf.AddSource(2, 11, z, r);
  z << 0.9;
  ekf.AddSource(3, 11, z, r);
  z << 0.35;
  ekf.UpdateSource(1, z, r);
  Eigen::Vector3d p3;
  Eigen::Matrix3d c3;
  ekf.SourcePoint(3, &p3, &c3);
  const int dim = ekf.dim();
  ekf.RemoveSource(2);
  ekf.RemoveAnchor(11);  // source 3 still uses it: kept
  EXPECT_TRUE(ekf.HasAnchor(11));
  EXPECT_EQ(ekf.dim(), dim - 2);
  Eigen::Vector3d q3;
  Eigen::Matrix3d d3;
  ekf.SourcePoint(3, &q3, &d3);
  EXPECT_LT((q3 - p3).norm(), 1e-12);
  EXPECT_LT((d3 - c3).norm(), 1e-12);
  ekf.RemoveSource(1);
  ekf.RemoveAnchor(10);
  EXPECT_FALSE(ekf.HasAnchor(10));
  EXPECT_EQ(ekf.dim(), dim - 7);
  ekf.SourcePoint(3, &q3, &d3);
  EXPECT_LT((q3 - p3).norm(), 1e-12);
  EXPECT_LT((d3 - c3).norm(), 1e-12);
  EXPECT_EQ(ekf.source_ids(), std::vector<int64_t>{3});
}

// Back-propagation with the localisation map's own state leaves the sound map unchanged,
// and moving a shared anchor moves the source along with it (K12 = P_SC P_C^-1).
TEST(IdpEkf, BackPropagationMovesSourcesWithAnchors) {
  IdpEkf::Options o;
  IdpEkf loc(o), snd(o);
  Eigen::Matrix3d p0 = Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal();
  loc.Reset(Pose2(0, 0, 0), p0);
  snd.Reset(Pose2(0, 0, 0), p0);
  loc.AddAnchor(0);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(1, 1) * 0.01;
  snd.AddSource(1, 0, Eigen::VectorXd::Constant(1, 0.5), r);
  for (int k = 1; k < 20; ++k) {
    loc.Predict(Pose2(0.2, 0, 0), Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal());
    Pose2 cur;
    std::vector<std::pair<int64_t, Pose2>> anchors;
    Eigen::MatrixXd cov;
    loc.SharedState({0}, &cur, &anchors, &cov);
    snd.BackPropagate(cur, anchors, cov);
    const double pose[3] = {cur.x, cur.y, cur.yaw};
    const Eigen::Vector3d src(4, 3, 0);
    double z[2];
    PointObservation(pose, src.data(), false, o.mount, z);
    snd.UpdateSource(1, Eigen::VectorXd::Constant(1, z[0]), r);
  }
  Eigen::Vector3d before, after;
  Eigen::Matrix3d c;
  snd.SourcePoint(1, &before, &c);
  // The localisation map learns that the anchor was 1 m further along +y (a loop closure).
  Pose2 cur = snd.current();
  std::vector<std::pair<int64_t, Pose2>> anchors = {{0, Pose2(0, 1.0, 0)}};
  Eigen::MatrixXd cov = Eigen::MatrixXd::Identity(6, 6) * 1e-6;
  cur.y += 1.0;
  snd.BackPropagate(cur, anchors, cov);
  snd.SourcePoint(1, &after, &c);
  EXPECT_NEAR(after.y() - before.y(), 1.0, 0.05);
  EXPECT_NEAR(after.x() - before.x(), 0.0, 0.05);
}

// Without the regression of eq. 4.25, SLAM's correction of an anchor moves its sources rigidly
// with it and moves nothing else. For one anchor whose source hangs fully from it, that is what
// the regression does too; they part where the bearings have correlated the inverse depth with
// several poses (the lab's caller: 2.3 m by regression, 0.1 m rigidly, for one correction).
// Returns the source after the correction; *rigid: where a rigid move with the anchor takes it,
// *moved_m: how far that is from where it was.
Eigen::Vector3d SourceAfterAnchorCorrection(bool back_propagate_sources, Eigen::Vector3d* rigid,
                                            double* moved_m) {
  IdpEkf::Options o;
  o.back_propagate_sources = back_propagate_sources;
  IdpEkf snd(o);
  snd.Reset(Pose2(0, 0, 0), Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal());
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(1, 1) * 1e-3;
  const Eigen::Vector3d src(5, 2, 0);
  for (int k = 0; k < 15; ++k) {
    if (k > 0) snd.Predict(Pose2(0.2, 0, 0), Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal());
    const Pose2 x = snd.current();
    const double pose[3] = {x.x, x.y, x.yaw};
    double z[2];
    PointObservation(pose, src.data(), false, o.mount, z);
    if (k == 0)
      snd.AddSource(1, 0, Eigen::VectorXd::Constant(1, z[0]), r);
    else
      snd.UpdateSource(1, Eigen::VectorXd::Constant(1, z[0] + 0.01), r);  // biased bearings
  }
  Eigen::Matrix3d c;
  Eigen::Vector3d before;
  snd.SourcePoint(1, &before, &c);
  // SLAM re-estimates the anchor 0.1 m to the side and 1.5 deg turned.
  const Pose2 old_anchor = snd.anchor(0);
  const Pose2 new_anchor(old_anchor.x, old_anchor.y + 0.1, old_anchor.yaw + 1.5 * M_PI / 180);
  snd.BackPropagate(snd.current(), {{0, new_anchor}}, Eigen::MatrixXd::Identity(6, 6) * 1e-6);
  Eigen::Vector3d after;
  snd.SourcePoint(1, &after, &c);
  const Pose2 moved = Compose(new_anchor, Between(old_anchor, Pose2(before.x(), before.y(), 0)));
  *rigid = Eigen::Vector3d(moved.x, moved.y, before.z());
  *moved_m = (*rigid - before).head<2>().norm();
  return after;
}

TEST(IdpEkf, WithoutRegressionSourcesMoveRigidlyWithTheirAnchors) {
  Eigen::Vector3d rigid;
  double moved_m = 0;
  const Eigen::Vector3d kept = SourceAfterAnchorCorrection(false, &rigid, &moved_m);
  EXPECT_GT(moved_m, 0.1);  // 0.1 m and 1.5 deg at ~5 m
  EXPECT_LT((kept - rigid).head<2>().norm(), 1e-9);
  const Eigen::Vector3d regressed = SourceAfterAnchorCorrection(true, &rigid, &moved_m);
  EXPECT_LT((regressed - rigid).head<2>().norm(), 0.01);
}

TEST(Experiments, MapsSourcesWithTable41Settings) {
  Sim2dConfig c;
  c.seed = 5;
  const Sim2dData d = Simulate2d(c);
  for (Method m : {Method::kEkfOdometry, Method::kJointOdometry}) {
    const RunResult res = RunMethod(d, m);
    printf("%s rms %.3f conv %.2f n %d\n", MethodName(m), res.score.rms_m, res.score.convergence_rate, res.score.num_sources);
    EXPECT_EQ(res.score.num_sources, 8);
    EXPECT_LT(res.score.rms_m, 0.35);  // Table 4.1 Part I odometry: accurate mapping (Figs. 4.3-4.4)
  }
  c.landmarks = true;
  c.odo_sigma_m = 0.02;
  c.odo_sigma_rad = 5 * M_PI / 180;
  const Sim2dData d2 = Simulate2d(c);
  for (Method m : {Method::kCiSubmaps, Method::kFullEkf, Method::kJoint}) {
    const RunResult res = RunMethod(d2, m);
    printf("%s rms %.3f conv %.2f n %d t %.3f step %.4f\n", MethodName(m), res.score.rms_m, res.score.convergence_rate, res.score.num_sources, res.total_seconds, res.sound_step_ms_mean);
    EXPECT_LT(res.score.rms_m, 0.35);  // Part II: typical odometry + landmarks (Figs. 4.6, 4.10)
  }
}

// Fig. 4.5 (reduced: 3 runs per cell): worse odometry, worse map, for both methods.
TEST(Experiments, Fig45ErrorGrowsWithOdometryNoise) {
  for (Method m : {Method::kEkfOdometry, Method::kJointOdometry}) {
    double rms[2] = {0, 0}, conv[2] = {0, 0};
    const double scales[2] = {1, 32};
    for (int s = 0; s < 2; ++s)
      for (int r = 0; r < 3; ++r) {
        Sim2dConfig c;
        c.odo_sigma_m = 0.001 * scales[s];
        c.odo_sigma_rad = 0.016 * scales[s] * M_PI / 180;
        c.seed = 1000 + r;
        const RunResult res = RunMethod(Simulate2d(c), m);
        rms[s] += res.score.rms_m / 3;
        conv[s] += res.score.convergence_rate / 3;
      }
    printf("%s: x1 rms %.3f conv %.2f | x32 rms %.3f conv %.2f\n", MethodName(m), rms[0], conv[0], rms[1], conv[1]);
    EXPECT_LT(rms[0], 0.35);
    EXPECT_GT(rms[1], 1.5 * rms[0]);
    EXPECT_LT(conv[1], conv[0]);
  }
}

// Fig. 4.11 (reduced: 2 runs, 45 m and 125 m): the CI method is as accurate as the full EKF,
// and joint optimisation is at least as good.
TEST(Experiments, Fig411CiMatchesFullEkf) {
  for (double side : {10.0, 30.0}) {
    double rms[3] = {0, 0, 0};
    const Method methods[3] = {Method::kCiSubmaps, Method::kFullEkf, Method::kJoint};
    for (int r = 0; r < 2; ++r) {
      const Sim2dData d = Simulate2d(Fig411Config(side, r));
      for (int i = 0; i < 3; ++i) rms[i] += RunMethod(d, methods[i]).score.rms_m / 2;
    }
    printf("side %.0f m: ci %.3f full-ekf %.3f joint %.3f\n", side, rms[0], rms[1], rms[2]);
    EXPECT_NEAR(rms[0], rms[1], 0.1 * rms[1] + 0.02);
    EXPECT_LE(rms[2], rms[0] + 0.02);
    EXPECT_LT(rms[0], 0.6);
  }
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
