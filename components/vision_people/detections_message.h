#pragma once
// The people confirmed in one frame as the people_detections_t that sarmap-vision-people
// publishes on PEOPLE_VISUAL (camera optical frame): position and covariance, the direction
// with its covariance, the cue (RGB-D or depth only), height and confidence. No transport, so
// the node and the in-process mission share it.

#include <cstdint>
#include <string>
#include <vector>

#include "sarmap/people_detections_t.hpp"
#include "vision_people/confirmation_tracker.h"

namespace sarmap {
namespace vision_people {

// Direction in the camera optical frame (z forward, x right, y down): azimuth positive to
// the left, elevation positive up, with the covariance propagated from the position's.
void FillDirection(const Eigen::Vector3d& position_camera, const Eigen::Matrix3d& covariance,
                   sarmap::person_detection_t* out);

sarmap::people_detections_t DetectionsMessage(const std::vector<ConfirmedPerson>& confirmed,
                                              int64_t utime, const std::string& sensor_id);

}  // namespace vision_people
}  // namespace sarmap
