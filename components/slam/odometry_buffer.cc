#include "slam/odometry_buffer.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace slam {

namespace {
constexpr double kDegToRad = M_PI / 180.0;
constexpr double kWindowS = 30.0;     // odometry kept this long
constexpr double kMaxHoldS = 0.5;     // At() this far outside the window holds the nearest sample
constexpr double kMaxReorderS = 1.0;  // older than the newest by more: rejected
}  // namespace

bool OdometryBuffer::Add(double time_s, const Rigid2d& pose, std::string* why, bool* reordered) {
  if (reordered) *reordered = false;
  auto reject = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (!std::isfinite(time_s) || !pose.translation().allFinite() || !std::isfinite(pose.yaw_rad())) {
    return reject("odometry not finite");
  }
  if (!samples_.empty()) {
    const OdometrySample& last = samples_.back();
    // Some logs stamp messages in bursts (Intel): a sample slightly older than the previous
    // one is kept in arrival order at the previous time rather than dropped.
    if (time_s < last.time_s - kMaxReorderS)
      return reject("odometry more than 1 s out of time order");
    if (time_s < last.time_s) {
      if (reordered) *reordered = true;
      time_s = last.time_s;
    }
    const double dt = time_s - last.time_s;
    const double d = (pose.translation() - last.odom_from_base.translation()).norm();
    const double a =
        std::abs(std::remainder(pose.yaw_rad() - last.odom_from_base.yaw_rad(), 2 * M_PI));
    const bool jump = d > input_.max_odometry_jump_m ||
                      d > input_.max_odometry_speed_mps * std::max(dt, 0.05) ||
                      a > input_.max_odometry_turn_radps * std::max(dt, 0.05);
    if (jump) {
      // A jump that persists (the next message agrees with it) is an odometry reset: start a
      // new segment, across which no motion is predicted. A single outlier stays rejected.
      if (have_pending_jump_ &&
          (pose.translation() - pending_jump_.odom_from_base.translation()).norm() <
              input_.max_odometry_speed_mps * std::max(time_s - pending_jump_.time_s, 0.05)) {
        have_pending_jump_ = false;
        ++segment_;
        samples_.push_back({pending_jump_.time_s, pending_jump_.odom_from_base, segment_});
        samples_.push_back({time_s, pose, segment_});
        return true;
      }
      have_pending_jump_ = true;
      pending_jump_ = {time_s, pose, segment_};
      return reject("odometry jump of " + std::to_string(d) + " m / " +
                    std::to_string(a / kDegToRad) + " deg in " + std::to_string(dt) + " s");
    }
  }
  have_pending_jump_ = false;
  samples_.push_back({time_s, pose, segment_});
  while (samples_.size() > 2 && samples_.front().time_s < time_s - kWindowS) samples_.pop_front();
  return true;
}

bool OdometryBuffer::At(double time_s, Rigid2d* pose, int* segment) const {
  if (samples_.empty()) return false;
  auto it = std::lower_bound(samples_.begin(), samples_.end(), time_s,
                             [](const OdometrySample& s, double t) { return s.time_s < t; });
  if (it == samples_.end() || time_s >= samples_.back().time_s) {
    // Slightly newer than the last odometry: hold the last pose (in turns, extrapolate: below).
    // (At the time of the last odometry, too: samples kept in arrival order share that time,
    // the last one is newest.)
    const double ahead_s = time_s - samples_.back().time_s;
    if (ahead_s > kMaxHoldS) return false;
    *pose = samples_.back().odom_from_base;
    *segment = samples_.back().segment;
    // A scan taken between readings of slower odometry (30 Hz depth scans, 20 Hz wheels) is
    // processed before the next reading. Held, the last reading puts the prediction of a turn
    // at 0.5 rad/s up to 1.4 deg behind, and the rotation prior pulls the match there:
    // extrapolate the last odometry step instead. Only in turns: driving straight, a held
    // reading leaves the prediction to the constant-velocity model of the matched poses
    // (PoseExtrapolator::Predict), which keeps the glass corridor's along-track drift at half of
    // what the extrapolated odometry gives (0.24 against 0.45 m after 19 m).
    if (local_.odometry_extrapolation_s > 0 && ahead_s <= local_.odometry_extrapolation_s &&
        samples_.size() >= 2) {
      const OdometrySample& a = samples_[samples_.size() - 2];
      const OdometrySample& b = samples_.back();
      const double dt = b.time_s - a.time_s;
      if (a.segment == b.segment && dt > 1e-3 && dt <= local_.odometry_extrapolation_s) {
        const double turn_radps =
            std::abs(
                std::remainder(b.odom_from_base.yaw_rad() - a.odom_from_base.yaw_rad(), 2 * M_PI)) /
            dt;
        if (turn_radps >= local_.odometry_extrapolation_min_turn_radps) {
          *pose = Interpolate(a.odom_from_base, b.odom_from_base, 1.0 + ahead_s / dt);
        }
      }
    }
    return true;
  }
  if (it->time_s == time_s || it == samples_.begin()) {
    if (it == samples_.begin() && it->time_s - time_s > kMaxHoldS) return false;
    *pose = it->odom_from_base;
    *segment = it->segment;
    return true;
  }
  const OdometrySample& a = *(it - 1);
  const OdometrySample& b = *it;
  if (a.segment != b.segment) {
    *pose = b.odom_from_base;
    *segment = b.segment;
    return true;
  }
  *pose =
      Interpolate(a.odom_from_base, b.odom_from_base, (time_s - a.time_s) / (b.time_s - a.time_s));
  *segment = a.segment;
  return true;
}

void OdometryBuffer::Reset(int segment) {
  samples_.clear();
  have_pending_jump_ = false;
  segment_ = segment;
}

}  // namespace slam
}  // namespace sarmap
