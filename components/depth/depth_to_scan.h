#pragma once
// Depth image -> planar laser scan (Sales 2014): every pixel is back-projected into the base
// frame; pixels whose height above the floor lies in [min_height_m, max_height_m] are
// obstacles, and each azimuth bin keeps the closest one, so table tops and overhangs within the
// robot's height count as obstacles (a single-row scan would miss them).
//
// For pixel (u, v) with depth d (metres): p_camera = d * ((u - cx) / fx, (v - cy) / fy, 1),
// p_base = base_from_camera * p_camera; azimuth = atan2(p_base.y, p_base.x) and range =
// hypot(p_base.x, p_base.y) (the scan is in the base frame, centred on the base origin).
// A bin gets:
//   - the range of the nearest surface among its in-band pixels (within [range_min_m,
//     range_max_m]): with range_noise_k = 0 their minimum; with range_noise_k > 0 (depth noise
//     sigma(r) = k r^2) the nearest surface's range: the pixels within W = surface_window_sigmas
//     * sigma(r_min) of the minimum r_min are that surface; the mean of those within W / 2 of
//     their median is its range (the median alone sits on one of the quantised depth levels).
//     The minimum of n noisy pixels of one wall lies ~2.5 sigma short for n ~ 70 (6 cm at 4 m
//     for a Kinect); a scan short by a range-dependent amount shrinks the map along the
//     direction of travel, and SLAM then falls behind by a share of every metre driven into
//     new space. Pixels up to W beyond range_max_m count too (a wall just inside the limit
//     has noisy pixels on both sides of it; keeping only the near ones pulls it closer), and
//     a surface whose range comes out beyond range_max_m is no return. The nearest surface's
//     range is within 1 mm of the truth on walls at 2-4.45 m;
//   - +inf ("no return": free up to the range limit) when it saw only pixels beyond
//     range_max_m, or in-band pixels nowhere but floor/ceiling pixels farther than
//     range_max_m;
//   - 0 (below range_min_m: "no information", ignored by SLAM) when it saw nothing valid.
// Each return also gets the range from which its surface is in the camera's view
// (visible_from_m): a surface whose top is at z_top below the lens height h is seen down to
// r = (h - z_top) / tan(a_down), with a_down the view's lowest ray below the horizontal (and
// likewise above the lens with the view's highest ray); nearer, the camera looks over it.
// Rubble 0.19 m high before a lens 0.55 m up with a 22.5 deg lower half-view leaves the view at
// 0.87 m, so a ray that passes over it closer is no sign that it is gone.
// Invalid pixels (0, or outside [range_min_m, range_max_m] along the optical axis) are skipped.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace sarmap {
namespace depth {

struct DepthToScanOptions {
  double min_height_m = 0.05;  // above the floor (base z)
  double max_height_m = 1.0;
  double range_min_m = 0.45;  // Kinect-class sensors read nothing closer
  double range_max_m = 4.5;
  int num_beams = 0;                 // 0: one per image column
  int row_step = 1;                  // use every n-th row (speed)
  double range_noise_k = 0;          // depth noise sigma = k r^2 (m); 0: a bin keeps its minimum
  double surface_window_sigmas = 6;  // the nearest surface spans this many sigma from the minimum
};

struct PinholeIntrinsics {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

struct PlanarScan {
  double angle_min_rad = 0;
  double angle_increment_rad = 0;
  float range_min_m = 0, range_max_m = 0;
  std::vector<float> ranges_m;
  // Per beam: for a return, the nearest range at which its surface is still in the camera's
  // view (at least range_min_m; +inf when never, for a camera that does not see the floor);
  // 0 for no return or no information.
  std::vector<float> visible_from_m;
  int in_band_pixels = 0;  // statistics
  int invalid_pixels = 0;
};

class DepthToScan {
 public:
  // base_from_camera: the camera optical frame (z forward, x right, y down) in the base frame.
  DepthToScan(const DepthToScanOptions& options, const PinholeIntrinsics& intrinsics,
              const Eigen::Isometry3d& base_from_camera);

  // depth: width*height values, row-major; metres = value * depth_unit_m; 0 = invalid.
  PlanarScan Convert(const uint16_t* depth, double depth_unit_m) const;

  const PinholeIntrinsics& intrinsics() const { return intrinsics_; }

 private:
  // Replaces each bin's minimum by its nearest surface's range (range_noise_k > 0).
  void NearestSurfaces(std::vector<float>* best) const;
  // Fills scan->visible_from_m from the returns' surfaces.
  void VisibleFrom(const std::vector<float>& best, PlanarScan* scan) const;

  DepthToScanOptions options_;
  PinholeIntrinsics intrinsics_;
  Eigen::Isometry3d base_from_camera_;
  // Per pixel: the base-frame ray direction for unit depth (x, y, z), precomputed.
  std::vector<Eigen::Vector3f> rays_;
  Eigen::Vector3f origin_;
  double angle_min_ = 0, angle_increment_ = 0;
  int num_beams_ = 0;
  // tan of the view's lowest ray below and highest ray above the horizontal (the smallest over
  // the image's bottom and top rows: the conservative edge); <= 0 when the view never reaches
  // that side.
  double tan_view_down_ = 0, tan_view_up_ = 0;
  // Per in-band pixel of the current frame: its bin, range and height (reused between frames).
  mutable std::vector<int> pixel_bin_, bin_start_;
  mutable std::vector<float> pixel_range_, pixel_z_, sorted_range_;
};

}  // namespace depth
}  // namespace sarmap
