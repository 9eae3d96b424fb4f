#pragma once
// Pose messages for the tests of the maps fed by POSE (not part of a library).

#include "common/time.h"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace common {
namespace testing_util {

// The robot at (x_m, 0) in the map frame facing +x, with a small covariance.
inline pose_t PoseAlongX(Utime utime, double x_m) {
  pose_t m{};
  m.header.utime = utime;
  m.header.frame = "map";
  m.position_m[0] = x_m;
  m.orientation[0] = 1;
  for (int i = 0; i < 6; ++i) m.covariance[7 * i] = 1e-4;
  return m;
}

}  // namespace testing_util
}  // namespace common
}  // namespace sarmap
