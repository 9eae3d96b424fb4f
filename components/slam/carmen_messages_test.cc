// CARMEN records as sarmap messages (carmen_messages.h): odometry as a planar pose about +z,
// a laser line with its own geometry and CARMEN's maximum reading as no return.
#include "slam/carmen_messages.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sarmap {
namespace slam {
namespace {

TEST(CarmenMessagesTest, OdometryIsAPlanarPoseAboutZ) {
  CarmenOdometry o;
  o.time_s = 12.25;
  o.x_m = 3;
  o.y_m = -1;
  o.theta_rad = 2.0;
  o.tv_mps = 0.4;
  o.rv_radps = -0.1;
  const odometry_t m = ToOdometryMessage(o);
  EXPECT_EQ(m.header.utime, 12'250'000);
  EXPECT_EQ(m.header.frame, "odom");
  EXPECT_EQ(m.child_frame, "base");
  EXPECT_DOUBLE_EQ(m.position_m[0], 3);
  EXPECT_DOUBLE_EQ(m.position_m[1], -1);
  // q = (cos theta/2, 0, 0, sin theta/2): the heading comes back from it.
  EXPECT_DOUBLE_EQ(m.orientation[1], 0);
  EXPECT_DOUBLE_EQ(m.orientation[2], 0);
  EXPECT_NEAR(2 * std::atan2(m.orientation[3], m.orientation[0]), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.linear_velocity_mps[0], 0.4);
  EXPECT_DOUBLE_EQ(m.angular_velocity_radps[2], -0.1);
}

TEST(CarmenMessagesTest, ALaserLineKeepsItsGeometryAndItsMaximumIsNoReturn) {
  CarmenLaser l;
  l.time_s = 1.5;
  l.angle_min_rad = -1.5707;
  l.angle_increment_rad = 0.0174;
  l.range_max_m = 81.9;
  l.ranges_m = {1.0f, 81.9f, 2.5f};
  const laser_scan_t m = ToScanMessage(l);
  EXPECT_EQ(m.header.utime, 1'500'000);
  EXPECT_EQ(m.header.frame, "laser");
  EXPECT_DOUBLE_EQ(m.angle_min_rad, -1.5707);
  EXPECT_DOUBLE_EQ(m.angle_increment_rad, 0.0174);
  ASSERT_EQ(m.num_ranges, 3);
  EXPECT_EQ(m.ranges_m, l.ranges_m);
  EXPECT_EQ(m.num_intensities, 0);
  // A range outside [range_min, range_max] is no return: the 81.9 m reading lies just above.
  EXPECT_LT(m.range_max_m, m.ranges_m[1]);
  EXPECT_GE(m.range_max_m, m.ranges_m[2]);
  EXPECT_NEAR(m.range_max_m, 81.9f, 1e-4);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
