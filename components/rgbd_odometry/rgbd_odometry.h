#pragma once
// 6-DoF visual odometry of a hand-held RGB-D rig (a Kinect: depth camera + colour camera, and
// later the 4-microphone linear array along the rig's +y axis, Su 2017 ch. 5) from OpenCV's
// rgbd module (dense photometric RgbdOdometry, ICPOdometry, RgbdICPOdometry, FastICPOdometry).
// No LCM and no OpenCV in this header (pimpl), so users only pull in Eigen.
//
// Frames:
//   optical  the depth camera's optical frame: z forward, x right, y down (OpenCV, PCL).
//   rig      the project's BODY convention attached to the same origin: x forward, y left,
//            z up. rig_from_optical maps optical z -> rig x, optical x -> rig -y, optical
//            y -> rig -z (RigFromOptical()).
//   world    the rig frame of the first frame (for the optical poses: the optical frame of
//            the first frame), so world_from_rig is the identity at the first frame.
//
// Tracking: every frame is aligned to the last KEYFRAME (not to the previous frame: less
// drift while the rig moves slowly or stands still), starting from the last frame-to-frame
// motion (constant velocity, scaled by the time step) or from the frame's motion prior. A frame
// becomes the new keyframe when the motion since the keyframe exceeds keyframe_translation_m or
// keyframe_rotation_deg.
//
// Failure: a frame with too little valid depth, an alignment that OpenCV reports as failed,
// an implausible frame-to-frame motion (max_frame_*), or a result whose depth overlap with the
// keyframe is too small (min_overlap_fraction) gives status kLost: the pose is held at the
// last good pose, the failure is counted, and the keyframe is dropped. The next frame with
// enough valid depth becomes the new keyframe at the held pose (status kReinitialised): the
// motion during the lost frames is not recovered (the pose has a gap; the covariance model
// adds relocalisation_sigma_* per such gap). A malformed input (empty, sizes that do not
// match, bad intrinsics or unit, missing image for an image method, time not increasing)
// gives kInvalidInput and leaves the state untouched. Nothing throws.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"

namespace sarmap {
namespace rgbd_odometry {

struct RgbdOdometryOptions {
  // rgbd (photometric + depth warp, Steinbruecker 2011), icp (point-to-plane, KinectFusion
  // style), rgbd_icp (both energies), fast_icp (OpenCV's KinectFusion ICP; ignores the initial
  // guess, min/max depth and max_points_part). Default chosen by measurement (README).
  std::string method = "rgbd";
  double image_scale = 0.5;        // 1 = full resolution; 0.5 halves width and height (speed)
  double min_depth_m = 0.3;        // closer readings are invalid
  double max_depth_m = 4.0;        // farther readings are invalid (Kinect noise grows as z^2)
  double max_depth_diff_m = 0.07;  // correspondences with a larger depth gap are rejected
  double max_points_part = 0.07;   // fraction of pixels used per pyramid level (rgbd, icp)
  // Iterations per pyramid level, finest first (its length is the number of levels).
  std::vector<int> iteration_counts = {7, 7, 7, 10};
  double min_gradient_magnitude = 10;  // rgbd, rgbd_icp: weaker intensity gradients unused
  double keyframe_translation_m = 0.10;
  double keyframe_rotation_deg = 10.0;
  // Plausibility of the motion between two consecutive processed frames (hand-held at 15 to
  // 30 Hz moves a few cm per frame): more than this is a failure, not a motion.
  double max_frame_translation_m = 0.25;
  double max_frame_rotation_deg = 25.0;
  // The initial guess of a frame (without a motion prior): the last motion scaled to this
  // time step, times this gain. 1 is a constant-velocity model; 0 starts from the last pose.
  // Where the scene leaves a direction unconstrained (a bare wall and the floor: the aligner
  // cannot see motion along both), constant velocity feeds back on itself and the pose runs
  // away along that direction (simulated lab: 0.03-0.08 m per frame while the camera stood,
  // 31 m in 90 s); from the last pose the unconstrained direction merely stands still.
  double velocity_prior_gain = 0.0;
  double min_valid_depth_fraction = 0.10;  // of the pixels; fewer valid -> lost
  // Of the current frame's valid points (sampled), the fraction that land on the keyframe's
  // depth within max_depth_diff_m after alignment; less -> lost (a diverged alignment or a
  // wrong local minimum). Measured: 0.88-0.97 when right (TUM, synthetic), 0.00-0.51 when
  // wrong (slambook2 steps of 23-73 cm without a prior).
  double min_overlap_fraction = 0.60;

  template <class V>
  void Visit(V& v) {
    v("method", method,
      "rgbd | icp | rgbd_icp | fast_icp (OpenCV rgbd module odometry; icp and fast_icp need "
      "no colour)",
      OneOf({"rgbd", "icp", "rgbd_icp", "fast_icp"}));
    v("image_scale", image_scale, "resize factor before odometry (1 full, 0.5 half: ~4x faster)",
      InRange(0.125, 1.0));
    v("min_depth_m", min_depth_m, "depth readings closer than this are invalid", NonNegative());
    v("max_depth_m", max_depth_m, "depth readings farther than this are invalid");
    v("max_depth_diff_m", max_depth_diff_m, "reject correspondences with a larger depth gap",
      Positive());
    v("max_points_part", max_points_part, "fraction of pixels used per level (rgbd, icp)");
    v("iteration_counts", iteration_counts, "iterations per pyramid level, finest level first");
    v("min_gradient_magnitude", min_gradient_magnitude,
      "rgbd, rgbd_icp: pixels with a weaker intensity gradient are not used", NonNegative());
    v("keyframe_translation_m", keyframe_translation_m,
      "new keyframe when the rig moved farther than this from the keyframe", Positive());
    v("keyframe_rotation_deg", keyframe_rotation_deg,
      "new keyframe when the rig turned more than this from the keyframe", Positive());
    v("max_frame_translation_m", max_frame_translation_m,
      "larger motion between consecutive frames is a failure (lost)", Positive());
    v("max_frame_rotation_deg", max_frame_rotation_deg,
      "larger rotation between consecutive frames is a failure (lost)", InRange(1e-6, 180));
    v("velocity_prior_gain", velocity_prior_gain,
      "initial guess = last motion x this (1: constant velocity; 0: the last pose, safer where "
      "walls are bare)",
      InRange(0.0, 1.0));
    v("min_valid_depth_fraction", min_valid_depth_fraction,
      "fewer valid depth pixels than this fraction -> lost", InRange(0, 1));
    v("min_overlap_fraction", min_overlap_fraction,
      "fewer aligned points agreeing with the keyframe's depth than this fraction -> lost",
      InRange(0, 1));
  }
  void Validate(common::Validator& c) const {
    c.That(max_depth_m > min_depth_m, "max_depth_m", "must be > min_depth_m");
    c.That(max_points_part > 0 && max_points_part <= 1, "max_points_part", "must be in (0, 1]");
    c.That(!iteration_counts.empty() && iteration_counts.size() <= 6, "iteration_counts",
           "needs 1 to 6 levels");
    for (int n : iteration_counts) c.That(n >= 1, "iteration_counts", "each must be >= 1");
  }
};

// Pose uncertainty that grows with the path: standard deviations
//   position: position_sigma_m + position_drift * distance travelled
//             + relocalisation_sigma_m * sqrt(relocalisations)
//   rotation: rotation_sigma_deg + rotation_drift_deg_per_m * distance
//             + rotation_drift * rotation travelled
//             + relocalisation_sigma_deg * sqrt(relocalisations)
// on the diagonal of a 6x6 (x y z roll pitch yaw) covariance (world axes, no correlation).
struct PoseCovarianceOptions {
  double position_sigma_m = 0.001;
  double position_drift = 0.02;  // fraction of the distance travelled (typical dense VO: 1-3 %)
  double rotation_sigma_deg = 0.1;
  double rotation_drift_deg_per_m = 1.0;
  double rotation_drift = 0.02;          // fraction of the accumulated rotation
  double relocalisation_sigma_m = 0.05;  // per lost/reinitialised gap
  double relocalisation_sigma_deg = 5.0;

  template <class V>
  void Visit(V& v) {
    v("position_sigma_m", position_sigma_m, "position standard deviation at the start", Positive());
    v("position_drift", position_drift, "position sigma grows by this fraction of the path",
      NonNegative());
    v("rotation_sigma_deg", rotation_sigma_deg, "rotation standard deviation at the start",
      Positive());
    v("rotation_drift_deg_per_m", rotation_drift_deg_per_m, "rotation sigma growth per metre",
      NonNegative());
    v("rotation_drift", rotation_drift, "rotation sigma grows by this fraction of the turning",
      NonNegative());
    v("relocalisation_sigma_m", relocalisation_sigma_m,
      "position sigma added (in quadrature) per tracking loss", NonNegative());
    v("relocalisation_sigma_deg", relocalisation_sigma_deg,
      "rotation sigma added (in quadrature) per tracking loss", NonNegative());
  }
};

struct PinholeCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels, of the depth image
};

// One RGB-D frame. Depth is registered to the image (same size and intrinsics).
struct RgbdFrame {
  int64_t utime = 0;  // capture time, microseconds; must increase from frame to frame
  int width = 0, height = 0;
  std::vector<uint16_t> depth;  // width*height, row-major; metres = value * depth_unit_m; 0 none
  double depth_unit_m = 0.001;
  // Optional for icp / fast_icp: width*height*image_channels bytes, 1 = grey, 3 = RGB order.
  std::vector<uint8_t> image;
  int image_channels = 0;
  PinholeCamera camera;
  // Optional motion prior (an IMU, wheel odometry, a coarse tracker): the rig's motion since
  // the previous frame given to Process, in the rig (body) frame. It replaces the
  // constant-velocity initial guess; large steps (frames tens of cm apart) only converge with
  // one. fast_icp ignores every initial guess.
  bool has_motion_prior = false;
  Eigen::Isometry3d previous_from_rig_prior = Eigen::Isometry3d::Identity();
};

enum class TrackingStatus {
  kInitialised,    // first frame: world = this frame, it is the first keyframe
  kTracking,       // aligned to the keyframe
  kReinitialised,  // first good frame after a loss: new keyframe at the held pose
  kLost,           // this frame failed; pose held at the last good pose
  kInvalidInput,   // malformed frame, ignored (state unchanged)
};
const char* TrackingStatusName(TrackingStatus status);

struct RgbdOdometryResult {
  TrackingStatus status = TrackingStatus::kInvalidInput;
  std::string message;  // why, for kLost and kInvalidInput
  int64_t utime = 0;
  Eigen::Isometry3d world_from_rig = Eigen::Isometry3d::Identity();      // body convention
  Eigen::Isometry3d world_from_optical = Eigen::Isometry3d::Identity();  // optical convention
  // Motion of the rig since the previous processed frame (identity unless kTracking).
  Eigen::Isometry3d previous_from_rig = Eigen::Isometry3d::Identity();
  bool keyframe = false;  // this frame became a keyframe
  double valid_depth_fraction = 0;
  double overlap_fraction = 0;  // see min_overlap_fraction (kTracking only)
  double distance_m = 0;        // path length so far
  double rotation_rad = 0;      // accumulated rotation so far
  int64_t relocalisations = 0;  // kReinitialised so far
  double compute_ms = 0;        // wall-clock time of this call (statistics only)

  bool ok() const {
    return status == TrackingStatus::kInitialised || status == TrackingStatus::kTracking ||
           status == TrackingStatus::kReinitialised;
  }
};

struct RgbdOdometryStats {
  int64_t frames = 0;  // every call
  int64_t tracked = 0;
  int64_t keyframes = 0;
  int64_t lost = 0;
  int64_t invalid = 0;
  int64_t relocalisations = 0;
};

// rig_from_optical: optical z -> rig x, optical x -> rig -y, optical y -> rig -z.
Eigen::Isometry3d RigFromOptical();
// world_from_rig from the optical-frame pose (both worlds at the first frame).
Eigen::Isometry3d RigPoseFromOpticalPose(const Eigen::Isometry3d& world_from_optical);

// 6x6 covariance (x y z roll pitch yaw) of a result, from PoseCovarianceOptions.
Eigen::Matrix<double, 6, 6> PoseCovariance(const PoseCovarianceOptions& options,
                                           const RgbdOdometryResult& result);

class RgbdOdometry {
 public:
  // Throws common::OptionsError on invalid options.
  explicit RgbdOdometry(const RgbdOdometryOptions& options);
  ~RgbdOdometry();
  RgbdOdometry(const RgbdOdometry&) = delete;
  RgbdOdometry& operator=(const RgbdOdometry&) = delete;

  // Processes one frame; never throws (errors are statuses).
  RgbdOdometryResult Process(const RgbdFrame& frame);
  // Forgets everything: the next frame starts a new world.
  void Reset();

  bool needs_image() const;  // rgbd and rgbd_icp use the intensity image
  const RgbdOdometryOptions& options() const;
  const RgbdOdometryStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbd_odometry
}  // namespace sarmap
