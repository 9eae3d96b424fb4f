// Message fields <-> geometry types: a pose and a covariance survive the round trip, and the
// planar block is (x, y, yaw) of the 6x6 (x y z roll pitch yaw) layout.

#include "common/message_conversions.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sarmap {
namespace common {
namespace {

TEST(MessageConversionsTest, APoseSurvivesTheRoundTrip) {
  const Rigid3d pose(
      Eigen::Vector3d(1.5, -2.0, 0.3),
      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized())));
  double position_m[3], orientation_wxyz[4];
  FromRigid3d(pose, position_m, orientation_wxyz);
  EXPECT_DOUBLE_EQ(position_m[1], -2.0);
  EXPECT_DOUBLE_EQ(orientation_wxyz[0], pose.rotation().w());  // w first
  const Rigid3d back = ToRigid3d(position_m, orientation_wxyz);
  EXPECT_LT((back.translation() - pose.translation()).norm(), 1e-12);
  EXPECT_LT(back.rotation().angularDistance(pose.rotation()), 1e-12);
}

TEST(MessageConversionsTest, TheCovarianceIsRowMajorAndThePlanarBlockIsXYYaw) {
  Eigen::Matrix<double, 6, 6> full;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) full(r, c) = 10 * r + c;
  double cov[36];
  FromCovariance6(full, cov);
  EXPECT_EQ(cov[1], 1.0);   // row 0, column 1
  EXPECT_EQ(cov[6], 10.0);  // row 1, column 0
  EXPECT_EQ(ToCovariance6(cov), full);
  const Eigen::Matrix3d planar = PlanarCovariance(cov);
  EXPECT_EQ(planar(0, 2), 5.0);   // x-yaw
  EXPECT_EQ(planar(2, 1), 51.0);  // yaw-y
  EXPECT_EQ(planar(2, 2), 55.0);
  // Back: the planar block in place, everything else zero.
  SetPlanarCovariance(planar, cov);
  const Eigen::Matrix<double, 6, 6> restored = ToCovariance6(cov);
  EXPECT_EQ(restored(5, 0), 50.0);
  EXPECT_EQ(restored(2, 2), 0.0);  // z
  EXPECT_EQ(restored(3, 5), 0.0);  // roll-yaw
  EXPECT_EQ(PlanarCovariance(restored), planar);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
