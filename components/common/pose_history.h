#pragma once
// A short history of timestamped poses (e.g. map_from_base from POSE) to look up the pose at
// a detection's capture time: linear interpolation of translation, slerp of rotation, and no
// extrapolation beyond a configurable gap.

#include <Eigen/Core>
#include <deque>
#include <optional>

#include "common/time.h"
#include "common/transform.h"

namespace sarmap {
namespace common {

struct StampedPose {
  Utime utime = 0;
  Rigid3d pose;
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();  // x y z r p y
};

class PoseHistory {
 public:
  // max_age_us: history kept behind the newest pose; max_gap_us: the largest distance in time
  // to a known pose that a lookup accepts (bracketing poses further apart than 2 * max_gap_us
  // are not interpolated).
  PoseHistory(Utime max_age_us, Utime max_gap_us) : max_age_us_(max_age_us), max_gap_us_(max_gap_us) {}

  // Poses older than the newest are inserted in order; an exact duplicate time replaces.
  void Add(const StampedPose& pose);
  std::optional<StampedPose> At(Utime utime) const;
  bool empty() const { return poses_.empty(); }
  Utime newest_utime() const { return poses_.empty() ? INT64_MIN : poses_.back().utime; }
  size_t size() const { return poses_.size(); }

 private:
  Utime max_age_us_;
  Utime max_gap_us_;
  std::deque<StampedPose> poses_;
};

}  // namespace common
}  // namespace sarmap
