#pragma once
// Where the next scan is in the local frame, before it is matched (the pose half of
// Cartographer's PoseExtrapolator), and the track of matched scans it predicts from:
//  - odometry (OdometryBuffer) moves the prediction from the reference: the last scan whose
//    odometry was fresh;
//  - odometry that did not change while the scans show motion is stale (some logs freeze it
//    for a second and then jump): a constant-velocity model of the last two matched poses
//    predicts, and the jump that follows is measured from the reference, so no motion is
//    counted twice;
//  - unchanged odometry on both sides of a scan (local.unchanged_odometry_means_stopped) is a
//    robot standing still: the stop pose is the prediction;
//  - after a restart from saved state, the first odometry bridges the motion made while the
//    process was down (when it is shorter than 10 m: a rebooted robot restarts its odometry).

#include "common/transform.h"
#include "slam/odometry_buffer.h"
#include "slam/slam_options.h"

namespace sarmap {
namespace slam {

struct ScanPrediction {
  Rigid2d local_pose;
  bool constant_velocity = false;  // extrapolated from the last two matches (no fresh odometry)
  bool fresh_odometry = false;     // the matched scan becomes the reference
  bool stopped = false;            // standing still: the stop pose
};

class PoseExtrapolator {
 public:
  explicit PoseExtrapolator(const LocalOptions& options) : options_(options) {}

  // The local pose predicted for a scan at time_s. The scan's odometry becomes last_odometry().
  ScanPrediction Predict(double time_s, const OdometryBuffer& odometry);
  // The scan predicted last was matched at `local_pose`.
  void AddMatch(double time_s, const Rigid2d& local_pose, const ScanPrediction& prediction);

  // The last matched scan.
  bool have_last() const { return have_last_; }
  double last_time_s() const { return last_time_s_; }
  const Rigid2d& last_pose() const { return last_pose_; }
  // The odometry of the scan predicted last.
  bool last_has_odometry() const { return last_has_odometry_; }
  const Rigid2d& last_odometry() const { return last_odometry_; }
  int last_segment() const { return last_segment_; }

  // Localisation only tracks the global pose itself: its scans and their odometry.
  void SetLast(double time_s, const Rigid2d& pose) {
    have_last_ = true;
    last_time_s_ = time_s;
    last_pose_ = pose;
  }
  void SetLastOdometry(bool has, const Rigid2d& odom_from_base, int segment) {
    last_has_odometry_ = has;
    if (has) last_odometry_ = odom_from_base, last_segment_ = segment;
  }
  // A new start at `pose`, in no time order with what came before.
  void Start(const Rigid2d& pose) {
    last_pose_ = pose;
    have_last_ = false;
  }

  // Back to a saved state's last scan. With `bridge`, the first odometry after it bridges the
  // motion made while the process was down (Predict).
  void Restore(bool have_last, double time_s, const Rigid2d& pose, bool has_odometry,
               const Rigid2d& odom_from_base, int segment, bool bridge);
  // After Restore: a scan with no odometry yet waits for the bridge, up to max_wait_s from the
  // first one that waited (true: wait); after that, none is expected.
  bool awaiting_bridge() const { return bridge_pending_; }
  bool KeepWaitingForBridge(double time_s, double max_wait_s);
  // The first scan after Restore was predicted across the gap.
  bool bridged() const { return bridged_; }
  void set_last_pose(const Rigid2d& pose) { last_pose_ = pose; }

 private:
  LocalOptions options_;
  bool have_last_ = false;
  double last_time_s_ = 0;
  Rigid2d last_pose_;
  bool last_has_odometry_ = false;
  Rigid2d last_odometry_;
  int last_segment_ = -1;
  bool have_prev_ = false;
  double prev_time_s_ = 0;
  Rigid2d prev_pose_;
  bool have_reference_ = false;
  Rigid2d reference_pose_, reference_odometry_;
  int reference_segment_ = -1;
  bool standing_still_ = false;  // unchanged odometry on both sides of the last scan
  // Restart from saved state.
  bool bridge_pending_ = false;
  double bridge_wait_start_s_ = -1;  // first scan that waited for odometry
  bool bridged_ = false;
  Rigid2d bridge_from_odometry_;  // the saved state's last odometry
};

}  // namespace slam
}  // namespace sarmap
