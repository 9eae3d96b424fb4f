#pragma once
// The safety layer's short memory of what the scan has shown, in the odometry frame.
//
// The explorer's grid lives in SLAM's map frame: what was mapped a while ago is offset from the
// robot by whatever SLAM's pose has drifted since, and a correction moves the pose and the grid
// at different moments. Odometry never jumps, and over a few metres it drifts by centimetres,
// so returns kept in its frame stay where they are relative to the base: an obstacle beside the
// base or nearer than the camera's minimum range is still known where the camera can no longer
// see it.
//
// Each return is kept in a cell of `cell_m` (the newest return in a cell wins) with the time it
// was seen. A kept return is dropped when
//   - it is older than `memory_s`, or further than `radius_m` from the base;
//   - later beams pass it: every beam within a cell of its bearing lies in the scan, reads
//     further than its range + `cell_m` (or no return), and sees down to its range (a depth
//     camera looks over low objects close by; passing over them is no sign they are gone). A
//     beam that grazes an edge does not clear the edge.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "common/transform.h"

namespace sarmap {
namespace explore {

struct Scan;

class LocalObstacles {
 public:
  LocalObstacles(double memory_s, double radius_m, double cell_m = 0.05)
      : memory_s_(memory_s), radius_m_(radius_m), cell_m_(cell_m) {}

  // The scan's returns seen from `odom_from_base` at `stamp_s`; forgets what has expired or
  // what this scan sees through.
  void Add(double stamp_s, const common::Rigid2d& odom_from_base, const Scan& scan);
  // Every kept return in the base frame of `odom_from_base`.
  std::vector<Eigen::Vector2d> InBase(const common::Rigid2d& odom_from_base) const;
  size_t size() const { return cells_.size(); }
  void Clear() { cells_.clear(); }

 private:
  struct Return {
    Eigen::Vector2d odom_m;
    double seen_s;
  };
  int64_t Key(const Eigen::Vector2d& odom_m) const;

  double memory_s_, radius_m_, cell_m_;
  double last_stamp_s_ = -std::numeric_limits<double>::infinity();
  std::unordered_map<int64_t, Return> cells_;
};

// The smallest distance from `p` to any of `points` (+inf when there are none).
double NearestDistance(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& points);

}  // namespace explore
}  // namespace sarmap
