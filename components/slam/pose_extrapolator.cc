#include "slam/pose_extrapolator.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace slam {

ScanPrediction PoseExtrapolator::Predict(double time_s, const OdometryBuffer& odometry) {
  ScanPrediction p;
  Rigid2d odom;
  int segment;
  const bool have_odom = odometry.At(time_s, &odom, &segment);
  const bool was_standing_still = standing_still_;
  standing_still_ = false;
  const double dt = time_s - last_time_s_;
  Rigid2d constant_velocity = last_pose_;
  if (have_prev_ && last_time_s_ >= prev_time_s_ && dt >= 0 && dt < 1.0) {
    const Rigid2d step = prev_pose_.inverse() * last_pose_;
    // Burst-stamped logs give tiny or huge time ratios: one step ahead, at most 2.
    const double gap = last_time_s_ - prev_time_s_;
    const double f = gap < 0.02 ? 1.0 : std::min(2.0, dt / gap);
    constant_velocity = last_pose_ * Rigid2d(f * step.translation(), f * step.yaw_rad());
  }
  last_has_odometry_ = have_odom;
  if (!have_odom) {
    p.constant_velocity = have_last_;
    p.local_pose = have_last_ ? constant_velocity : last_pose_;
    return p;
  }
  last_odometry_ = odom;
  last_segment_ = segment;
  if (bridge_pending_) {
    // First odometry after a restart from saved state: if the process (not the robot) was
    // restarted, the odometry frame is the same and bridges the motion made while we were down.
    // A robot that rebooted restarts its odometry near the identity; a bridge longer than
    // kMaxBridgeM is then not believed and the wide search finds the robot instead.
    constexpr double kMaxBridgeM = 10.0;
    bridge_pending_ = false;
    const Rigid2d bridge = bridge_from_odometry_.inverse() * odom;
    if (bridge.translation().norm() < kMaxBridgeM) {
      p.fresh_odometry = true;
      bridged_ = true;
      p.local_pose = last_pose_ * bridge;
      return p;
    }
  }
  if (!have_reference_ || segment != reference_segment_) {
    p.fresh_odometry = true;
    p.local_pose = last_pose_;
    return p;
  }
  const Rigid2d odom_delta = reference_odometry_.inverse() * odom;
  const bool frozen =
      odom_delta.translation().norm() < 1e-9 && std::abs(odom_delta.yaw_rad()) < 1e-9;
  // Odometry readings on both sides of the scan (not only the last one, held) that did not change
  // show a robot standing still; the held last reading alone shows nothing yet.
  // Once standing, a scan ahead of the newest reading is still standing.
  const bool odometry_after_scan = time_s <= odometry.newest().time_s;
  standing_still_ = frozen && options_.unchanged_odometry_means_stopped &&
                    (odometry_after_scan || was_standing_still);
  if (standing_still_) {
    // Standing still. Each scan is matched with the stop pose as its prior, not the previous
    // match: chaining priors is a proximal-point descent that walks down any slope of a weak
    // map (3 cm/s and 0.4 deg/s in the open-area simulation). The reference stays put.
    p.stopped = true;
    p.local_pose = reference_pose_;
    return p;
  }
  if (frozen) {
    p.constant_velocity = true;
    p.local_pose = constant_velocity;
    return p;
  }
  p.fresh_odometry = true;
  p.local_pose = reference_pose_ * odom_delta;
  return p;
}

void PoseExtrapolator::AddMatch(double time_s, const Rigid2d& local_pose,
                                const ScanPrediction& prediction) {
  if (prediction.fresh_odometry) {
    have_reference_ = true;
    reference_pose_ = local_pose;
    reference_odometry_ = last_odometry_;
    reference_segment_ = last_segment_;
  }
  have_prev_ = have_last_;
  prev_time_s_ = last_time_s_;
  prev_pose_ = last_pose_;
  have_last_ = true;
  last_time_s_ = time_s;
  last_pose_ = local_pose;
}

void PoseExtrapolator::Restore(bool have_last, double time_s, const Rigid2d& pose,
                               bool has_odometry, const Rigid2d& odom_from_base, int segment,
                               bool bridge) {
  have_last_ = have_last;
  last_time_s_ = time_s;
  last_pose_ = pose;
  last_odometry_ = odom_from_base;
  last_segment_ = segment;
  bridge_pending_ = has_odometry && bridge;
  bridge_wait_start_s_ = -1;
  bridged_ = false;
  bridge_from_odometry_ = odom_from_base;
  last_has_odometry_ = false;
  have_reference_ = false;
  have_prev_ = false;
}

bool PoseExtrapolator::KeepWaitingForBridge(double time_s, double max_wait_s) {
  if (bridge_wait_start_s_ < 0) bridge_wait_start_s_ = time_s;
  if (time_s - bridge_wait_start_s_ < max_wait_s) return true;
  bridge_pending_ = false;
  return false;
}

}  // namespace slam
}  // namespace sarmap
