#pragma once
// The floor seen by an RGB-D camera, found from the data with the configured mounting only as
// a prior:
//   1. RANSAC over a sparse sample of the cloud: plane hypotheses from three points, kept only
//      when they put the camera 0.3-2 m above the floor with at most +-25 deg of tilt (plus a
//      margin) and little roll; each scored by its inliers minus the points clearly below it
//      (nothing is seen through a floor, so a table top or a shelf above the floor loses to
//      the floor under it). The tracked and the configured planes are scored as hypotheses too.
//   2. least-squares refinement (PCA) on the inliers of the best hypothesis;
//   3. tracking: the camera's height and tilt smoothed over frames, reset on a discontinuity
//      (a jump larger than sensor noise and body sway, or a gap in time) and reported against
//      the configured mounting.
// No OpenCV, PCL or LCM here.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "common/options.h"

namespace sarmap {
namespace vision_people {

// A plane n.p + d = 0 in the camera frame with |n| = 1 and n pointing up, so that
// n.p + d is the height of p above the ground.
struct GroundPlane {
  Eigen::Vector3d normal = Eigen::Vector3d(0, -1, 0);
  double offset = 0.55;
  double Height(const Eigen::Vector3d& p) const { return normal.dot(p) + offset; }
  // From PCL's (a, b, c, d) convention (a x + b y + c z + d = 0, either orientation).
  static GroundPlane FromCoefficients(const Eigen::Vector4d& abcd);
};
// The floor (z = 0 of the base frame) seen from a camera mounted at base_from_camera.
GroundPlane GroundFromMounting(const Eigen::Matrix3d& base_R_camera,
                               const Eigen::Vector3d& base_t_camera);

// The camera's pose over the floor as a user describes a mounting: height of the optical
// centre above the floor, tilt of the optical axis below the horizon (positive: looking down)
// and roll about the optical axis (positive: the floor's up direction leans towards the
// image's +x, i.e. the camera is turned counter-clockwise as seen from behind it).
struct CameraMounting {
  double height_m = 0;
  double tilt_down_rad = 0;
  double roll_rad = 0;
};
CameraMounting MountingFromGround(const GroundPlane& ground);
GroundPlane GroundFromCameraMounting(const CameraMounting& mounting);

struct GroundOptions {
  bool refine = true;  // fit the floor per frame (false: the mounting plane)
  // RANSAC over the cloud.
  int sample_stride_px = 4;  // every n-th pixel in x and y
  int ransac_iterations = 200;
  int ransac_eval_points = 3000;  // hypotheses are scored on at most this many points
  double inlier_m = 0.03;         // + 2 sigma of the depth noise at the point's range
  double below_m = 0.12;  // points lower than this (+ 3 sigma) under a plane count against it
  double min_camera_height_m = 0.25;
  double max_camera_height_m = 2.2;
  double max_tilt_deg = 30;  // |tilt| of the optical axis against the floor
  double max_roll_deg = 20;
  double min_inlier_fraction = 0.04;  // of the sampled points; fewer: no floor in this frame
  // Voxel-level polish (points with free space above them), gated against the RANSAC plane.
  double band_m = 0.15;            // voxels within this of the RANSAC plane are floor candidates
  int min_voxels = 40;             // fewer floor candidates: keep the RANSAC plane
  double max_tilt_change_deg = 4;  // polished vs RANSAC plane
  double max_offset_change_m = 0.08;
  double removal_m = 0.06;  // voxels lower than this above the floor are removed
  // Tracking over frames.
  double smoothing = 0.3;        // weight of the new frame's estimate
  double reset_height_m = 0.12;  // a jump larger than this restarts the track
  double reset_angle_deg = 6;
  double reset_gap_s = 2.0;        // frames further apart than this (or out of order) restart it
  // An established track is restarted by a jump away from the mounting file only once fits that
  // agree with each other have disagreed with it this long (a box top or a table filling the
  // view for a moment is not the floor); a jump back to the mounting file restarts it at once.
  double reset_confirm_s = 2.0;
  int established_frames = 5;      // a track this long is trusted over the mounting file
  double mismatch_height_m = 0.1;  // track vs mounting file: reported beyond these
  double mismatch_angle_deg = 5;
  template <class V>
  void Visit(V& v) {
    v("refine", refine, "fit the floor per frame (false: always the mounting plane)");
    v("sample_stride_px", sample_stride_px, "RANSAC samples every n-th pixel in x and y",
      InRange(1, 16));
    v("ransac_iterations", ransac_iterations, "RANSAC plane hypotheses per frame",
      InRange(1, 10000));
    v("ransac_eval_points", ransac_eval_points, "hypotheses are scored on at most this many points",
      InRange(50, 1000000));
    v("inlier_m", inlier_m,
      "inlier distance (plus 2 sigma of the depth noise at the point's range)", Positive());
    v("below_m", below_m, "points this far (plus 3 sigma) under a hypothesis count against it",
      Positive());
    v("min_camera_height_m", min_camera_height_m, "lowest accepted camera height above the floor",
      Positive());
    v("max_camera_height_m", max_camera_height_m, "highest accepted camera height above the floor");
    v("max_tilt_deg", max_tilt_deg, "largest accepted tilt of the optical axis (up or down)",
      InRange(0, 80));
    v("max_roll_deg", max_roll_deg, "largest accepted roll about the optical axis", InRange(0, 80));
    v("min_inlier_fraction", min_inlier_fraction,
      "fewer floor points (fraction of the sample): no floor found in the frame", InRange(0, 1));
    v("band_m", band_m,
      "voxels within this distance of the RANSAC plane are floor candidates for the polish",
      Positive());
    v("min_voxels", min_voxels, "minimum floor voxels for the polish");
    v("max_tilt_change_deg", max_tilt_change_deg,
      "largest accepted tilt of the polished plane from the RANSAC plane", Positive());
    v("max_offset_change_m", max_offset_change_m,
      "largest accepted height change of the polished plane", Positive());
    v("removal_m", removal_m,
      "points closer than this to the floor are removed (Munaro: voxel size)", Positive());
    v("smoothing", smoothing,
      "weight of a new frame's floor in the tracked floor (1: no smoothing)", InRange(0.01, 1));
    v("reset_height_m", reset_height_m,
      "a camera height jump larger than this restarts the floor track", Positive());
    v("reset_angle_deg", reset_angle_deg,
      "a floor tilt jump larger than this restarts the floor track", Positive());
    v("reset_gap_s", reset_gap_s,
      "frames further apart in time (or out of order) restart the floor track", Positive());
    v("reset_confirm_s", reset_confirm_s,
      "an established floor track is restarted by a jump away from the mounting file only when "
      "the jumped-to floor persists this long (a box top filling the view is held off); 0: at "
      "once",
      NonNegative());
    v("established_frames", established_frames,
      "frames after which the tracked floor is trusted over the mounting file");
    v("mismatch_height_m", mismatch_height_m,
      "tracked vs configured camera height: reported beyond this", Positive());
    v("mismatch_angle_deg", mismatch_angle_deg,
      "tracked vs configured floor angle: reported beyond this", Positive());
  }
  void Validate(common::Validator& check) const {
    check.That(max_camera_height_m > min_camera_height_m, "max_camera_height_m",
               "must exceed min_camera_height_m");
  }
};

// Angle between two floor normals, degrees.
double AngleBetweenDeg(const GroundPlane& a, const GroundPlane& b);

struct FloorFit {
  bool found = false;
  GroundPlane plane;
  int sampled = 0;  // points sampled from the cloud
  int inliers = 0;  // of the final plane, among the sampled points
};

// RANSAC + least squares over an organized cloud (xyz, 3 floats per pixel, NaN = none;
// points nearer than min_range_m or farther than max_range_m are skipped). `hypotheses` (the
// tracked and the configured floor) are scored alongside the random ones. Deterministic.
FloorFit FitFloor(const float* xyz, int width, int height, double min_range_m, double max_range_m,
                  const GroundOptions& options, const std::vector<GroundPlane>& hypotheses);

// The floor tracked over frames.
class GroundTracker {
 public:
  GroundTracker(const GroundOptions& options, const GroundPlane& mounting);

  // One frame: `fit` is this frame's estimate (nullptr: none). Returns the floor to use: the
  // track, which a fit that jumps away from an established track joins only once the jump has
  // lasted reset_confirm_s (until then the fit is held off and the track is returned).
  GroundPlane Update(const GroundPlane* fit, int64_t utime);
  void Reset();

  bool has_track() const { return frames_ > 0; }
  bool established() const { return frames_ >= options_.established_frames; }
  const GroundPlane& tracked() const { return tracked_; }
  const GroundPlane& mounting() const { return mounting_; }
  int frames() const { return frames_; }
  int resets() const { return resets_; }
  bool last_update_reset() const { return last_reset_; }
  // This frame's fit jumped away from the track and was held off (reset_confirm_s).
  bool last_update_held_off() const { return last_held_off_; }
  int held_off() const { return held_off_; }  // fits held off so far
  // The established track disagrees with the configured mounting.
  bool mismatch() const;

 private:
  GroundOptions options_;
  GroundPlane mounting_;
  GroundPlane tracked_;
  int frames_ = 0;
  int resets_ = 0;
  bool last_reset_ = false;
  bool last_held_off_ = false;
  int held_off_ = 0;
  int64_t last_utime_ = 0;
  // Fits that jump away from the established track: the latest one, and since when fits that
  // agree with it have come.
  bool jumping_ = false;
  GroundPlane jump_;
  int64_t jump_since_utime_ = 0;

  bool Apart(const GroundPlane& a, const GroundPlane& b) const;
};

}  // namespace vision_people
}  // namespace sarmap
