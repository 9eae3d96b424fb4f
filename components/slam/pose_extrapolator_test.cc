#include "slam/pose_extrapolator.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace slam {
namespace {

using common::Rigid2d;

// Odometry samples 0.1 s apart at the given x positions (heading 0).
OdometryBuffer Odometry(const std::vector<double>& x_m) {
  OdometryBuffer odometry(InputOptions{}, LocalOptions{});
  for (size_t i = 0; i < x_m.size(); ++i)
    EXPECT_TRUE(odometry.Add(0.1 * i, Rigid2d(x_m[i], 0, 0), nullptr, nullptr));
  return odometry;
}

TEST(PoseExtrapolatorTest, OdometryMovesThePredictionFromTheReferenceScan) {
  PoseExtrapolator extrapolator{LocalOptions{}};
  const OdometryBuffer odometry = Odometry({0, 0.1, 0.2, 0.3});
  ScanPrediction p = extrapolator.Predict(0.0, odometry);
  EXPECT_TRUE(p.fresh_odometry);  // no reference yet: the scan becomes it
  extrapolator.AddMatch(0.0, Rigid2d(5, 5, 0), p);
  p = extrapolator.Predict(0.2, odometry);
  EXPECT_TRUE(p.fresh_odometry);
  EXPECT_NEAR(p.local_pose.translation().x(), 5.2, 1e-12);
  EXPECT_NEAR(p.local_pose.translation().y(), 5.0, 1e-12);
  EXPECT_TRUE(extrapolator.last_has_odometry());
  EXPECT_NEAR(extrapolator.last_odometry().translation().x(), 0.2, 1e-12);
}

TEST(PoseExtrapolatorTest, FrozenOdometryGivesConstantVelocityOrAStopPose) {
  // Odometry that stands at 0.1 m while the scans move 0.05 m per 0.1 s.
  const OdometryBuffer odometry = Odometry({0, 0.1, 0.1, 0.1, 0.1, 0.1});
  for (bool stopped_means_stopped : {false, true}) {
    LocalOptions options;
    options.unchanged_odometry_means_stopped = stopped_means_stopped;
    PoseExtrapolator extrapolator(options);
    ScanPrediction p = extrapolator.Predict(0.1, odometry);
    extrapolator.AddMatch(0.1, Rigid2d(1.0, 0, 0), p);
    p = extrapolator.Predict(0.2, odometry);
    extrapolator.AddMatch(0.2, Rigid2d(1.05, 0, 0), p);
    p = extrapolator.Predict(0.3, odometry);
    if (stopped_means_stopped) {
      EXPECT_TRUE(p.stopped);
      EXPECT_NEAR(p.local_pose.translation().x(), 1.0, 1e-12);  // the reference: the stop pose
    } else {
      EXPECT_TRUE(p.constant_velocity);
      EXPECT_NEAR(p.local_pose.translation().x(), 1.10, 1e-12);  // one more 0.05 m step
    }
  }
}

TEST(PoseExtrapolatorTest, AfterARestoreTheFirstOdometryBridgesTheGapUnlessItIsImplausible) {
  for (double odometry_x : {2.0, 30.0}) {
    PoseExtrapolator extrapolator{LocalOptions{}};
    // Saved: the last scan at (1, 0) with odometry at x = 0.5.
    extrapolator.Restore(true, 10.0, Rigid2d(1, 0, 0), true, Rigid2d(0.5, 0, 0), 0, true);
    EXPECT_TRUE(extrapolator.awaiting_bridge());
    EXPECT_TRUE(extrapolator.KeepWaitingForBridge(11.0, 1.0));
    OdometryBuffer odometry(InputOptions{}, LocalOptions{});
    ASSERT_TRUE(odometry.Add(11.5, Rigid2d(odometry_x, 0, 0), nullptr, nullptr));
    const ScanPrediction p = extrapolator.Predict(11.5, odometry);
    EXPECT_FALSE(extrapolator.awaiting_bridge());
    if (odometry_x < 10) {
      EXPECT_TRUE(extrapolator.bridged());
      EXPECT_NEAR(p.local_pose.translation().x(), 1.0 + (odometry_x - 0.5), 1e-12);
    } else {  // 29.5 m of odometry while down: a rebooted robot, not believed
      EXPECT_FALSE(extrapolator.bridged());
      EXPECT_NEAR(p.local_pose.translation().x(), 1.0, 1e-12);
    }
  }
  PoseExtrapolator waiting{LocalOptions{}};
  waiting.Restore(true, 10.0, Rigid2d(), true, Rigid2d(), 0, true);
  EXPECT_TRUE(waiting.KeepWaitingForBridge(11.0, 1.0));
  EXPECT_FALSE(waiting.KeepWaitingForBridge(12.0, 1.0));  // no odometry within 1 s: none expected
  EXPECT_FALSE(waiting.awaiting_bridge());
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
