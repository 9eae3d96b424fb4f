#pragma once
// Angles wrapped to (-pi, pi]: the one home of angle wrapping in sarmap.
//
// WrapAngle(double) is exact (std::remainder). The template serves Ceres jets (and any type
// with floor found by argument-dependent lookup):
//   wrap(a) = a + 2 pi floor((pi - a) / 2 pi),
// whose derivative is 1 everywhere but at the cut, so a residual that wraps keeps its
// Jacobian.

#include <cmath>

namespace sarmap {
namespace common {

inline double WrapAngle(double angle_rad) {
  angle_rad = std::remainder(angle_rad, 2.0 * M_PI);
  return angle_rad <= -M_PI ? angle_rad + 2.0 * M_PI : angle_rad;
}

template <typename T>
T WrapAngle(const T& angle_rad) {
  using std::floor;
  const T two_pi = T(2.0 * M_PI);
  return angle_rad + two_pi * floor((T(M_PI) - angle_rad) / two_pi);
}

}  // namespace common
}  // namespace sarmap
