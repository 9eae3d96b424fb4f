// PEOPLE_VISUAL as sarmap-vision-people publishes it, from the confirmed people of a frame.
#include "vision_people/detections_message.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sarmap {
namespace vision_people {
namespace {

ConfirmedPerson At(const Eigen::Vector3d& position_camera, bool hog_used, double confidence) {
  ConfirmedPerson c;
  c.track_id = 7;
  c.person.position_camera = position_camera;
  c.person.covariance = Eigen::Matrix3d::Identity() * 0.01;
  c.person.hog_used = hog_used;
  c.person.confidence = confidence;
  c.person.height_m = 1.7;
  return c;
}

TEST(DetectionsMessage, CarriesPositionDirectionAndCue) {
  // 1 m to the right of the optical axis (x right), 0.5 m below it (y down), 3 m ahead.
  const auto msg = DetectionsMessage(
      {At({1.0, 0.5, 3.0}, true, 0.8), At({-1.0, 0, 2.0}, false, 1.4)}, 1234, "kinect");
  EXPECT_EQ(msg.header.utime, 1234);
  EXPECT_EQ(msg.header.frame, "camera");
  EXPECT_EQ(msg.sensor_id, "kinect");
  ASSERT_EQ(msg.num_detections, 2);
  const auto& a = msg.detections[0];
  EXPECT_EQ(a.cue, static_cast<int8_t>(person_detection_t::CUE_SEEN_RGBD));
  EXPECT_TRUE(a.has_range);
  EXPECT_DOUBLE_EQ(a.position_m[0], 1.0);
  EXPECT_DOUBLE_EQ(a.position_m[2], 3.0);
  EXPECT_NEAR(a.azimuth_rad, std::atan2(-1.0, 3.0), 1e-12);  // to the right: negative
  EXPECT_NEAR(a.elevation_rad, std::atan2(-0.5, std::hypot(1.0, 3.0)), 1e-12);
  EXPECT_GT(a.direction_covariance[0], 0);
  EXPECT_FLOAT_EQ(a.confidence, 0.8f);
  const auto& b = msg.detections[1];
  EXPECT_EQ(b.cue, static_cast<int8_t>(person_detection_t::CUE_SEEN_DEPTH));
  EXPECT_GT(b.azimuth_rad, 0);          // to the left
  EXPECT_FLOAT_EQ(b.confidence, 1.0f);  // clamped
}

TEST(DetectionsMessage, NoPeopleIsAnEmptyMessage) {
  const auto msg = DetectionsMessage({}, 5, "kinect");
  EXPECT_EQ(msg.num_detections, 0);
  EXPECT_TRUE(msg.detections.empty());
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
