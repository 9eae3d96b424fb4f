#include "slam/packed_points.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace sarmap {
namespace slam {

PackedPoints::PackedPoints(const PointCloud& points) {
  float largest = 0;
  for (const Eigen::Vector2f& p : points) {
    if (std::isfinite(p.x()) && std::isfinite(p.y())) {
      largest = std::max(largest, std::max(std::abs(p.x()), std::abs(p.y())));
    }
  }
  // The smallest power of two with largest / step <= 32767 (from 2^-15 m up).
  int exponent = -15;
  while (exponent < 30 && largest > 32767.0f * std::ldexp(1.0f, exponent)) ++exponent;
  step_m_ = std::ldexp(1.0f, exponent);
  xy_.reserve(2 * points.size());
  for (const Eigen::Vector2f& p : points) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;  // never stored
    xy_.push_back(static_cast<int16_t>(std::lround(p.x() / step_m_)));
    xy_.push_back(static_cast<int16_t>(std::lround(p.y() / step_m_)));
  }
}

PackedPoints PackedPoints::FromRaw(float step_m, std::vector<int16_t> xy) {
  if (xy.empty() && step_m == 0) return PackedPoints();  // as default-constructed
  int exponent = 0;
  if (!(step_m > 0) || !std::isfinite(step_m) || std::frexp(step_m, &exponent) != 0.5f) {
    throw std::invalid_argument("packed points: step " + std::to_string(step_m) +
                                " m is not a power of two");
  }
  if (xy.size() % 2 != 0) throw std::invalid_argument("packed points: odd coordinate count");
  PackedPoints packed;
  packed.step_m_ = step_m;
  packed.xy_ = std::move(xy);
  return packed;
}

PointCloud PackedPoints::Unpack() const {
  PointCloud points(size());
  for (size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector2f(xy_[2 * i], xy_[2 * i + 1]) * step_m_;
  }
  return points;
}

}  // namespace slam
}  // namespace sarmap
