#pragma once
// Messages for the people map's tests (not part of a library): the robot's pose and a person
// seen straight ahead of the camera.

#include "common/testing/pose_messages.h"
#include "common/time.h"
#include "sarmap/people_detections_t.hpp"

namespace sarmap {
namespace people_map {
namespace testing_util {

using common::testing_util::PoseAlongX;

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
