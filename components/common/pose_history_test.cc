#include "common/pose_history.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace common {
namespace {

StampedPose Planar(Utime t, double x, double yaw) {
  StampedPose p;
  p.utime = t;
  p.pose = Rigid3d::FromRigid2d(Rigid2d(x, 0, yaw));
  return p;
}

TEST(PoseHistoryTest, InterpolatesBetweenAndRefusesFarExtrapolation) {
  PoseHistory h(10'000'000, 200'000);
  h.Add(Planar(1'000'000, 0.0, 0.0));
  h.Add(Planar(1'200'000, 1.0, 0.4));
  h.Add(Planar(1'100'000, 0.5, 0.2));  // out of order is fine
  const auto mid = h.At(1'150'000);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->pose.translation().x(), 0.75, 1e-9);
  EXPECT_NEAR(mid->pose.ToRigid2d().yaw_rad(), 0.3, 1e-9);
  EXPECT_TRUE(h.At(1'300'000));   // within the gap after the newest: held
  EXPECT_FALSE(h.At(1'500'000));  // too far after
  EXPECT_FALSE(h.At(500'000));    // too far before
  EXPECT_EQ(h.size(), 3u);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
