#include "slam/motion_filter.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace slam {
namespace {

using common::Rigid2d;

TEST(MotionFilterTest, ANodeOnceTheScanMovedTurnedOrWaitedEnough) {
  LocalOptions options;
  options.node_max_distance_m = 0.2;
  options.node_max_angle_deg = 1.0;
  options.node_max_time_s = 5.0;
  MotionFilter filter(options);
  EXPECT_TRUE(filter.Moved(0.0, Rigid2d()));  // the first scan
  filter.NodeAdded(0.0, Rigid2d());
  EXPECT_FALSE(filter.Moved(1.0, Rigid2d(0.19, 0, 0.9 * M_PI / 180)));
  EXPECT_TRUE(filter.Moved(1.0, Rigid2d(0.21, 0, 0)));
  EXPECT_TRUE(filter.Moved(1.0, Rigid2d(0, 0, 1.1 * M_PI / 180)));
  EXPECT_TRUE(filter.Moved(5.1, Rigid2d()));
  // Angles wrap: -179.5 deg to +179.8 deg is 0.7 deg.
  filter.NodeAdded(6.0, Rigid2d(1, 1, -179.5 * M_PI / 180));
  EXPECT_FALSE(filter.Moved(6.5, Rigid2d(1, 1, 179.8 * M_PI / 180)));
  filter.Restore(10.0, Rigid2d(3, 0, 0));
  EXPECT_FALSE(filter.Moved(11.0, Rigid2d(3.1, 0, 0)));
  EXPECT_DOUBLE_EQ(filter.last_time_s(), 10.0);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
