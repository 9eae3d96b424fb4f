#include "common/transform.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace common {
namespace {

TEST(Rigid2dTest, ComposeAndInverse) {
  const Rigid2d map_from_base(1.0, 2.0, M_PI / 2);
  const Eigen::Vector2d p = map_from_base * Eigen::Vector2d(1.0, 0.0);
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 3.0, 1e-12);
  const Rigid2d identity = map_from_base * map_from_base.inverse();
  EXPECT_NEAR(identity.translation().norm(), 0.0, 1e-12);
  EXPECT_NEAR(identity.yaw_rad(), 0.0, 1e-12);
  EXPECT_NEAR(WrapAngle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, 1e-12);
}

TEST(Rigid3dTest, RoundTripsThroughPlanar) {
  const Rigid2d planar(0.5, -1.0, 2.0);
  const Rigid2d back = Rigid3d::FromRigid2d(planar).ToRigid2d();
  EXPECT_NEAR(back.translation().x(), 0.5, 1e-12);
  EXPECT_NEAR(back.yaw_rad(), 2.0, 1e-12);
  const Rigid3d t(Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized())));
  const Eigen::Vector3d x(0.2, -0.4, 1.0);
  EXPECT_NEAR(((t.inverse() * t) * x - x).norm(), 0.0, 1e-12);
}

TEST(FramedTest, RefusesTransformsThatDoNotChain) {
  const FramedRigid2d map_from_odom{"map", "odom", Rigid2d(1, 0, 0)};
  const FramedRigid2d odom_from_base{"odom", "base", Rigid2d(0, 1, 0)};
  const FramedRigid2d map_from_base = map_from_odom * odom_from_base;
  EXPECT_EQ(map_from_base.parent, "map");
  EXPECT_EQ(map_from_base.child, "base");
  EXPECT_NEAR(map_from_base.transform.translation().y(), 1.0, 1e-12);
  EXPECT_THROW(odom_from_base * map_from_odom, FrameMismatch);
  EXPECT_EQ(map_from_base.inverse().parent, "base");
}

}  // namespace
}  // namespace common
}  // namespace sarmap
