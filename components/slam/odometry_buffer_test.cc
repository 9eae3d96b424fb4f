#include "slam/odometry_buffer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sarmap {
namespace slam {
namespace {

// Odometry at 10 Hz driving +x at 1 m/s.
OdometryBuffer Driving(int samples, LocalOptions local = {}) {
  OdometryBuffer buffer(InputOptions{}, local);
  for (int i = 0; i < samples; ++i)
    EXPECT_TRUE(buffer.Add(0.1 * i, Rigid2d(0.1 * i, 0, 0), nullptr, nullptr));
  return buffer;
}

TEST(OdometryBufferTest, InterpolatesBetweenSamplesAndHoldsJustAfterTheNewest) {
  const OdometryBuffer buffer = Driving(11);
  Rigid2d pose;
  int segment = -1;
  ASSERT_TRUE(buffer.At(0.55, &pose, &segment));
  EXPECT_NEAR(pose.translation().x(), 0.55, 1e-12);
  EXPECT_EQ(segment, 0);
  ASSERT_TRUE(buffer.At(1.3, &pose, &segment));  // 0.3 s after the newest: held
  EXPECT_NEAR(pose.translation().x(), 1.0, 1e-12);
  EXPECT_FALSE(buffer.At(1.6, &pose, &segment));   // more than 0.5 s after
  EXPECT_FALSE(buffer.At(-0.6, &pose, &segment));  // more than 0.5 s before
}

TEST(OdometryBufferTest, ExtrapolatesTheLastStepInTurnsOnly) {
  LocalOptions local;
  local.odometry_extrapolation_s = 0.2;
  local.odometry_extrapolation_min_turn_radps = 0.1;
  OdometryBuffer turning(InputOptions{}, local);
  for (int i = 0; i < 5; ++i)
    turning.Add(0.1 * i, Rigid2d(0, 0, 0.05 * i), nullptr, nullptr);  // 0.5 rad/s
  Rigid2d pose;
  int segment;
  ASSERT_TRUE(turning.At(0.5, &pose, &segment));
  EXPECT_NEAR(pose.yaw_rad(), 0.25, 1e-12);  // one more step
  const OdometryBuffer straight = Driving(5, local);
  ASSERT_TRUE(straight.At(0.5, &pose, &segment));
  EXPECT_NEAR(pose.translation().x(), 0.4, 1e-12);  // held
}

TEST(OdometryBufferTest, RejectsOutliersAndStartsASegmentAtAConfirmedReset) {
  OdometryBuffer buffer = Driving(5);
  std::string why;
  // One outlier 50 m away: rejected, and the stream goes on in the same segment.
  EXPECT_FALSE(buffer.Add(0.5, Rigid2d(50, 0, 0), &why, nullptr));
  EXPECT_NE(why.find("jump"), std::string::npos);
  EXPECT_TRUE(buffer.Add(0.6, Rigid2d(0.5, 0, 0), nullptr, nullptr));
  EXPECT_EQ(buffer.segment(), 0);
  // A reset: the odometry restarts near the origin and stays there.
  EXPECT_FALSE(buffer.Add(0.7, Rigid2d(-20, 0, 0), nullptr, nullptr));
  EXPECT_TRUE(buffer.Add(0.8, Rigid2d(-19.9, 0, 0), nullptr, nullptr));
  EXPECT_EQ(buffer.segment(), 1);
  Rigid2d pose;
  int segment;
  // Across the reset nothing is interpolated: the newer segment's pose.
  ASSERT_TRUE(buffer.At(0.65, &pose, &segment));
  EXPECT_EQ(segment, 1);
  EXPECT_NEAR(pose.translation().x(), -20, 1e-12);
  EXPECT_FALSE(buffer.Add(0.9, Rigid2d(std::nan(""), 0, 0), &why, nullptr));
  EXPECT_EQ(why, "odometry not finite");
}

TEST(OdometryBufferTest, KeepsSlightlyOlderSamplesAtTheNewestTime) {
  OdometryBuffer buffer = Driving(5);
  bool reordered = false;
  EXPECT_TRUE(buffer.Add(0.35, Rigid2d(0.41, 0, 0), nullptr, &reordered));
  EXPECT_TRUE(reordered);
  EXPECT_DOUBLE_EQ(buffer.newest().time_s, 0.4);
  EXPECT_FALSE(buffer.Add(-1.0, Rigid2d(0.4, 0, 0), nullptr, &reordered));  // > 1 s old
  buffer.Reset(7);
  EXPECT_TRUE(buffer.empty());
  EXPECT_TRUE(buffer.Add(2.0, Rigid2d(5, 0, 0), nullptr, nullptr));
  EXPECT_EQ(buffer.newest().segment, 7);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
