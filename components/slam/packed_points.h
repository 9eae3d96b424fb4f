#pragma once
// Points stored in 16-bit fixed point: each coordinate an integer multiple of one step per
// cloud, the smallest power of two (in metres) that keeps the largest coordinate within
// +-32767 steps: 2^-15 m (0.03 mm) for returns within 1 m, 2^-10 m (1 mm) within 32 m,
// 2^-8 m (4 mm) within 128 m. Half the bytes of float points. The step is a power of two, so
// packing unpacked points again gives the same bits (a state file written as floats and read
// back packs to the same cloud).

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "slam/grid.h"

namespace sarmap {
namespace slam {

class PackedPoints {
 public:
  PackedPoints() = default;
  explicit PackedPoints(const PointCloud& points);

  // The stored form (a state file writes it as it is): step_m (a power of two) and x0, y0,
  // x1, y1, ... in steps (an empty cloud never packed has step 0). Throws
  // std::invalid_argument when `step_m` is not a positive power of two (or 0 with no points) or
  // `xy` has an odd count.
  static PackedPoints FromRaw(float step_m, std::vector<int16_t> xy);
  const std::vector<int16_t>& raw() const { return xy_; }

  PointCloud Unpack() const;
  bool empty() const { return xy_.empty(); }
  size_t size() const { return xy_.size() / 2; }
  float step_m() const { return step_m_; }
  size_t MemoryBytes() const { return xy_.capacity() * sizeof(int16_t); }

 private:
  float step_m_ = 0;
  std::vector<int16_t> xy_;  // x0, y0, x1, y1, ...
};

// A node's scan in its base frame, packed (see RangeData).
struct PackedRangeData {
  PackedRangeData() = default;
  explicit PackedRangeData(const RangeData& data)
      : origin(data.origin), hits(data.hits), misses(data.misses) {}
  RangeData Unpack() const { return {origin, hits.Unpack(), misses.Unpack()}; }
  size_t MemoryBytes() const { return hits.MemoryBytes() + misses.MemoryBytes(); }

  Eigen::Vector2f origin = Eigen::Vector2f::Zero();
  PackedPoints hits;
  PackedPoints misses;
};

}  // namespace slam
}  // namespace sarmap
