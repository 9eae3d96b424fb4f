#pragma once
// The odometry half of a pose extrapolator (Cartographer's PoseExtrapolator keeps odometry the
// same way): the odometry odom_from_base of the last 30 s, checked as it arrives, and the pose
// at any time in that window for predicting a scan's motion.
//  - Checks: a sample that is not finite, more than 1 s out of time order, or a jump (faster than
//    input.max_odometry_speed_mps / _turn_radps, or longer than max_odometry_jump_m) is rejected.
//    A sample slightly out of time order (logs stamped in bursts) is kept, at the previous time.
//  - Segments: a jump the next sample confirms is an odometry reset; a new segment starts, and no
//    motion is predicted across segments. A single outlier stays rejected.
//  - At(t): interpolated between the samples around t; up to 0.5 s after the newest sample the
//    newest is held, or in a turn (local.odometry_extrapolation_*) its last step extrapolated.

#include <deque>
#include <string>

#include "common/transform.h"
#include "slam/slam_options.h"

namespace sarmap {
namespace slam {

using common::Rigid2d;

struct OdometrySample {
  double time_s = 0;
  Rigid2d odom_from_base;
  int segment = 0;
};

class OdometryBuffer {
 public:
  OdometryBuffer(const InputOptions& input, const LocalOptions& local)
      : input_(input), local_(local) {}

  // Adds odom_from_base at time_s. False when it is rejected (`why` says why). `reordered` is
  // set when the sample was older than the newest and is kept at the newest one's time.
  bool Add(double time_s, const Rigid2d& odom_from_base, std::string* why, bool* reordered);
  // odom_from_base at time_s and the segment it belongs to; false outside the window (more than
  // 0.5 s before the oldest or after the newest sample) or with no odometry.
  bool At(double time_s, Rigid2d* odom_from_base, int* segment) const;

  bool empty() const { return samples_.empty(); }
  const OdometrySample& newest() const { return samples_.back(); }
  // The segment the next sample joins.
  int segment() const { return segment_; }
  // Everything dropped; the next sample starts `segment` (after a restart from saved state: no
  // motion is predicted from the odometry before it).
  void Reset(int segment);

 private:
  InputOptions input_;
  LocalOptions local_;
  std::deque<OdometrySample> samples_;
  int segment_ = 0;
  bool have_pending_jump_ = false;  // a jump waiting for the next sample to confirm it
  OdometrySample pending_jump_;
};

}  // namespace slam
}  // namespace sarmap
