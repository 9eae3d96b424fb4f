#pragma once
// Messages for the people map's tests (not part of a library): the robot's pose and a person
// seen straight ahead of the camera.

#include "common/time.h"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace people_map {
namespace testing_util {

// The robot at (x_m, 0) facing +x, with a small covariance.
inline pose_t Pose(common::Utime utime, double x_m) {
  pose_t m{};
  m.header.utime = utime;
  m.header.frame = "map";
  m.position_m[0] = x_m;
  m.orientation[0] = 1;
  for (int i = 0; i < 6; ++i) m.covariance[7 * i] = 1e-4;
  return m;
}

// One person straight ahead of the camera, forward_m along its optical axis.
inline people_detections_t Seen(common::Utime utime, double forward_m) {
  people_detections_t m{};
  m.header.utime = utime;
  m.header.frame = "camera";
  person_detection_t d{};
  d.cue = person_detection_t::CUE_SEEN_DEPTH;
  d.has_range = true;
  d.position_m[1] = 0.55 - 0.85;  // centre 0.85 m above the floor, camera 0.55 m up
  d.position_m[2] = forward_m;
  d.position_covariance[0] = d.position_covariance[4] = d.position_covariance[8] = 0.01;
  d.confidence = 0.9f;
  m.detections.push_back(d);
  m.num_detections = 1;
  return m;
}

}  // namespace testing_util
}  // namespace people_map
}  // namespace sarmap
