#pragma once
// For the vision tests (not part of a library): a Kinect's nominal intrinsics as a
// message, scaled to a resolution.

#include "sarmap/camera_intrinsics_t.hpp"

namespace sarmap {
namespace vision_people {
namespace testing_util {

inline camera_intrinsics_t KinectIntrinsics(int width, int height) {
  camera_intrinsics_t k{};
  k.width = width;
  k.height = height;
  k.fx = k.fy = 525.0 * width / 640.0;
  k.cx = (width - 1) / 2.0;
  k.cy = (height - 1) / 2.0;
  return k;
}

}  // namespace testing_util
}  // namespace vision_people
}  // namespace sarmap
