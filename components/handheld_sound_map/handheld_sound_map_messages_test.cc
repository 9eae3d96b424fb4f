// The hand-held node's message conversions (handheld_sound_map_messages.h): the sensor frame of
// the linear array, rig poses, the array's angles as beta and heard directions.
#include "handheld_sound_map/handheld_sound_map_messages.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sarmap {
namespace sound_map {
namespace {

TEST(HandheldSoundMapMessagesTest, TheSensorFrameHasTheArrayAlongY) {
  common::ExtrinsicsOptions rig_from_mic;  // identity: the array (mic x) along the rig's x
  rig_from_mic.z_m = -0.03;
  const Eigen::Isometry3d rig_from_sensor = RigFromSensor(rig_from_mic);
  // The sensor's +y is the array's axis, mic +x; the sensor's +x is mic -y.
  EXPECT_TRUE((rig_from_sensor.linear() * Eigen::Vector3d::UnitY())
                  .isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE((rig_from_sensor.linear() * Eigen::Vector3d::UnitX())
                  .isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_NEAR(rig_from_sensor.translation().z(), -0.03, 1e-12);
  // The shipped mounting (yaw pi/2, the bar along the rig's y): the array along the rig's y.
  rig_from_mic.yaw_rad = M_PI / 2;
  EXPECT_TRUE((RigFromSensor(rig_from_mic).linear() * Eigen::Vector3d::UnitY())
                  .isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST(HandheldSoundMapMessagesTest, RigPosesMustBeFiniteWithAUnitQuaternion) {
  sarmap::pose_t msg{};
  msg.position_m[0] = 1;
  msg.position_m[1] = 2;
  msg.position_m[2] = 3;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  msg.orientation[0] = q.w();
  msg.orientation[3] = q.z();
  Eigen::Isometry3d pose;
  ASSERT_TRUE(IsometryFromPose(msg, &pose));
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(pose.linear().isApprox(q.toRotationMatrix(), 1e-12));

  sarmap::pose_t not_unit = msg;
  not_unit.orientation[0] *= 2;
  EXPECT_FALSE(IsometryFromPose(not_unit, &pose));
  sarmap::pose_t nan_position = msg;
  nan_position.position_m[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(IsometryFromPose(nan_position, &pose));
}

TEST(HandheldSoundMapMessagesTest, LinearAnglesBecomeBetaAndOtherKindsAreCounted) {
  sarmap::doa_t msg{};
  sarmap::doa_source_t s{};
  s.kind = sarmap::doa_source_t::KIND_ANGLE_1D;
  s.track_id = 4;
  s.azimuth_rad = M_PI / 3;  // alpha to the axis
  s.covariance[0] = 0.0025;
  msg.sources.push_back(s);
  sarmap::doa_source_t planar = s;
  planar.kind = sarmap::doa_source_t::KIND_AZIMUTH;
  msg.sources.push_back(planar);
  msg.num_sources = 2;
  int64_t skipped = 0;
  const std::vector<LinearArraySoundMap::Doa> doas = LinearDoasFromMessage(msg, &skipped);
  ASSERT_EQ(doas.size(), 1u);
  EXPECT_EQ(skipped, 1);
  EXPECT_EQ(doas[0].track_id, 4);
  EXPECT_NEAR(doas[0].beta_rad, M_PI / 2 - M_PI / 3, 1e-12);  // from broadside
  EXPECT_NEAR(doas[0].sigma_rad, 0.05, 1e-12);

  sarmap::people_detections_t people{};
  sarmap::person_detection_t heard{};
  heard.cue = sarmap::person_detection_t::CUE_HEARD;
  heard.azimuth_rad = 0.2;
  heard.direction_covariance[0] = 0.01;
  sarmap::person_detection_t seen = heard;
  seen.cue = sarmap::person_detection_t::CUE_SEEN_RGBD;
  sarmap::person_detection_t lost = heard;
  lost.azimuth_rad = std::numeric_limits<double>::infinity();
  people.detections = {heard, seen, lost};
  people.num_detections = 3;
  const std::vector<LinearArraySoundMap::Doa> directions = HeardLinearDirections(people);
  ASSERT_EQ(directions.size(), 1u);
  EXPECT_NEAR(directions[0].beta_rad, M_PI / 2 - 0.2, 1e-12);
  EXPECT_NEAR(directions[0].sigma_rad, 0.1, 1e-12);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
