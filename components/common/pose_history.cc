#include "common/pose_history.h"

#include <algorithm>

namespace sarmap {
namespace common {

void PoseHistory::Add(const StampedPose& pose) {
  auto it = std::lower_bound(poses_.begin(), poses_.end(), pose.utime,
                             [](const StampedPose& p, Utime t) { return p.utime < t; });
  if (it != poses_.end() && it->utime == pose.utime) {
    *it = pose;
  } else {
    poses_.insert(it, pose);
  }
  while (!poses_.empty() && poses_.front().utime < poses_.back().utime - max_age_us_) poses_.pop_front();
}

std::optional<StampedPose> PoseHistory::At(Utime utime) const {
  if (poses_.empty()) return std::nullopt;
  auto after = std::lower_bound(poses_.begin(), poses_.end(), utime,
                                [](const StampedPose& p, Utime t) { return p.utime < t; });
  if (after == poses_.end()) {
    const StampedPose& last = poses_.back();
    if (utime - last.utime > max_gap_us_) return std::nullopt;
    StampedPose out = last;
    out.utime = utime;
    return out;
  }
  if (after->utime == utime || after == poses_.begin()) {
    if (after->utime - utime > max_gap_us_) return std::nullopt;
    StampedPose out = *after;
    out.utime = utime;
    return out;
  }
  const StampedPose& a = *(after - 1);
  const StampedPose& b = *after;
  if (b.utime - a.utime > 2 * max_gap_us_) return std::nullopt;
  const double s = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  StampedPose out;
  out.utime = utime;
  out.pose = Rigid3d((1 - s) * a.pose.translation() + s * b.pose.translation(),
                     a.pose.rotation().slerp(s, b.pose.rotation()));
  out.covariance = (1 - s) * a.covariance + s * b.covariance;
  return out;
}

}  // namespace common
}  // namespace sarmap
