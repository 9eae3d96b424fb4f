#include "slam/packed_points.h"

#include <algorithm>
#include <cmath>

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

PointCloud PackedPoints::Unpack() const {
  PointCloud points(size());
  for (size_t i = 0; i < points.size(); ++i) {
    points[i] = Eigen::Vector2f(xy_[2 * i], xy_[2 * i + 1]) * step_m_;
  }
  return points;
}

PackedRangeData::PackedRangeData(const RangeData& data)
    : origin(data.origin), hits(data.hits), misses(data.misses) {
  // PackedPoints leaves out non-finite points: index the hits as stored.
  int32_t stored = 0;
  for (size_t k = 0; k < data.hits.size(); ++k) {
    if (!std::isfinite(data.hits[k].x()) || !std::isfinite(data.hits[k].y())) continue;
    const float from_m = k < data.hit_visible_from_m.size() ? data.hit_visible_from_m[k] : 0.f;
    if (from_m > 0.f && std::isfinite(from_m)) visible_from.push_back({stored, from_m});
    ++stored;
  }
}

RangeData PackedRangeData::Unpack() const {
  RangeData data{origin, hits.Unpack(), misses.Unpack(), {}};
  if (!visible_from.empty()) {
    data.hit_visible_from_m.assign(data.hits.size(), 0.f);
    for (const VisibleFrom& v : visible_from) data.hit_visible_from_m[v.hit] = v.from_m;
  }
  return data;
}

}  // namespace slam
}  // namespace sarmap
