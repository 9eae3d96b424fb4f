#include "depth/depth_to_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sarmap {
namespace depth {

DepthToScan::DepthToScan(const DepthToScanOptions& options, const PinholeIntrinsics& in,
                         const Eigen::Isometry3d& base_from_camera)
    : options_(options), intrinsics_(in), base_from_camera_(base_from_camera) {
  if (in.width <= 0 || in.height <= 0 || !(in.fx > 0) || !(in.fy > 0)) {
    throw std::invalid_argument("depth-to-scan: invalid camera intrinsics");
  }
  const Eigen::Matrix3f r = base_from_camera.rotation().cast<float>();
  origin_ = base_from_camera.translation().cast<float>();
  rays_.resize(static_cast<size_t>(in.width) * in.height);
  for (int v = 0; v < in.height; ++v) {
    for (int u = 0; u < in.width; ++u) {
      const Eigen::Vector3f cam((u - in.cx) / in.fx, (v - in.cy) / in.fy, 1.0);
      rays_[static_cast<size_t>(v) * in.width + u] = r * cam;
    }
  }
  // Azimuth span: the image's left and right edges at the principal row, seen from the base
  // origin at a nominal 2 m (a little margin for rows that look sideways).
  auto azimuth = [&](double u) {
    const Eigen::Vector3f p = origin_ + 2.0f * (r * Eigen::Vector3f((u - in.cx) / in.fx, 0, 1));
    return std::atan2(p.y(), p.x());
  };
  double a0 = azimuth(0), a1 = azimuth(in.width - 1);
  if (a0 > a1) std::swap(a0, a1);
  // The view's vertical edges: the bottom and top rows' rays, the shallowest of each row.
  auto elevation_tan = [&](int v, double sign) {
    double best = std::numeric_limits<double>::infinity();
    for (int u = 0; u < in.width; ++u) {
      const Eigen::Vector3f& ray = rays_[static_cast<size_t>(v) * in.width + u];
      best = std::min(best, sign * ray.z() / std::max(1e-9f, std::hypot(ray.x(), ray.y())));
    }
    return best;
  };
  const double bottom = elevation_tan(in.height - 1, -1.0), top = elevation_tan(0, -1.0);
  // Rows run top to bottom in the image; with the camera upside down they swap.
  tan_view_down_ = std::max(bottom, top);
  tan_view_up_ = std::max(elevation_tan(0, 1.0), elevation_tan(in.height - 1, 1.0));
  const double margin = 0.02;
  num_beams_ = options.num_beams > 0 ? options.num_beams : in.width;
  angle_min_ = a0 - margin;
  angle_increment_ = (a1 - a0 + 2 * margin) / std::max(1, num_beams_ - 1);
}

PlanarScan DepthToScan::Convert(const uint16_t* depth, double depth_unit_m) const {
  PlanarScan scan;
  scan.angle_min_rad = angle_min_;
  scan.angle_increment_rad = angle_increment_;
  scan.range_min_m = static_cast<float>(options_.range_min_m);
  scan.range_max_m = static_cast<float>(options_.range_max_m);
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> best(num_beams_, inf);
  std::vector<uint8_t> seen_far(num_beams_, 0);
  const float unit = static_cast<float>(depth_unit_m);
  const float zmin = static_cast<float>(options_.min_height_m);
  const float zmax = static_cast<float>(options_.max_height_m);
  const float rmin = static_cast<float>(options_.range_min_m);
  const float rmax = static_cast<float>(options_.range_max_m);
  const int w = intrinsics_.width, h = intrinsics_.height;
  const int step = std::max(1, options_.row_step);
  const bool nearest_surface = options_.range_noise_k > 0;
  pixel_bin_.clear();
  pixel_range_.clear();
  pixel_z_.clear();
  // With the nearest surface, pixels up to a window beyond range_max_m still count: a wall just
  // inside the limit has noisy pixels on both sides of it, and keeping only the near ones
  // would pull it closer; a surface whose range comes out beyond the limit is no return.
  const float rlimit = nearest_surface
                           ? rmax + static_cast<float>(options_.surface_window_sigmas *
                                                       options_.range_noise_k * rmax * rmax)
                           : rmax;
  for (int v = 0; v < h; v += step) {
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      const float d = depth[i] * unit;
      if (!(d > 0) || d < rmin) {
        ++scan.invalid_pixels;
        continue;
      }
      const Eigen::Vector3f p = origin_ + d * rays_[i];
      const double az = std::atan2(p.y(), p.x());
      const int bin = static_cast<int>(std::lround((az - angle_min_) / angle_increment_));
      if (bin < 0 || bin >= num_beams_) continue;
      if (d > rlimit) {  // beyond the sensor's trusted range: free up to the limit
        seen_far[bin] = 1;
        continue;
      }
      const float range = std::hypot(p.x(), p.y());
      if (p.z() < zmin || p.z() > zmax) {
        // Floor or ceiling: the bin is free at least up to this pixel.
        if (d > rmax || range >= rmax * 0.95f) seen_far[bin] = 1;
        continue;
      }
      if (range > rlimit) {  // off-axis: the horizontal range is what the scan limits
        seen_far[bin] = 1;
        continue;
      }
      ++scan.in_band_pixels;
      best[bin] = std::min(best[bin], range);
      pixel_bin_.push_back(bin);
      pixel_range_.push_back(range);
      pixel_z_.push_back(p.z());
    }
  }
  if (nearest_surface) {
    NearestSurfaces(&best);
    for (int b = 0; b < num_beams_; ++b) {
      if (std::isfinite(best[b]) && best[b] > rmax) {  // a surface beyond the limit
        best[b] = inf;
        seen_far[b] = 1;
      }
    }
  }
  scan.ranges_m.resize(num_beams_);
  for (int b = 0; b < num_beams_; ++b) {
    if (std::isfinite(best[b])) {
      scan.ranges_m[b] = best[b];
    } else {
      scan.ranges_m[b] = seen_far[b] ? inf : 0.0f;  // no return / no information
    }
  }
  VisibleFrom(best, &scan);
  return scan;
}

void DepthToScan::VisibleFrom(const std::vector<float>& best, PlanarScan* scan) const {
  // The surface of a bin: its pixels within the nearest-surface window of the return (5 cm
  // without a noise model). Its height span [z_bottom, z_top] against the lens height h: the
  // view reaches z_top < h from (h - z_top) / tan(a_down) on, z_bottom > h from
  // (z_bottom - h) / tan(a_up) on, and a surface across h from the sensor's minimum range on.
  const float inf = std::numeric_limits<float>::infinity();
  const float k = static_cast<float>(options_.range_noise_k);
  const float sigmas = static_cast<float>(options_.surface_window_sigmas);
  std::vector<float> z_top(num_beams_, -inf), z_bottom(num_beams_, inf);
  for (size_t i = 0; i < pixel_bin_.size(); ++i) {
    const int b = pixel_bin_[i];
    const float r = best[b];
    if (!std::isfinite(r)) continue;
    const float window = k > 0 ? sigmas * k * r * r : 0.05f;
    if (std::abs(pixel_range_[i] - r) > window) continue;
    z_top[b] = std::max(z_top[b], pixel_z_[i]);
    z_bottom[b] = std::min(z_bottom[b], pixel_z_[i]);
  }
  const double lens_z = origin_.z();
  scan->visible_from_m.assign(num_beams_, 0.0f);
  for (int b = 0; b < num_beams_; ++b) {
    if (!(std::isfinite(scan->ranges_m[b]) && scan->ranges_m[b] >= scan->range_min_m)) continue;
    double from = options_.range_min_m;
    if (z_top[b] < lens_z) {
      from = tan_view_down_ > 0 ? (lens_z - z_top[b]) / tan_view_down_ : inf;
    } else if (z_bottom[b] > lens_z) {
      from = tan_view_up_ > 0 ? (z_bottom[b] - lens_z) / tan_view_up_ : inf;
    }
    scan->visible_from_m[b] = static_cast<float>(std::max(from, options_.range_min_m));
  }
}

void DepthToScan::NearestSurfaces(std::vector<float>* best) const {
  // Group the in-band ranges by bin (counting sort), then per bin take the median of those
  // within the window above the bin's minimum.
  bin_start_.assign(num_beams_ + 1, 0);
  for (int b : pixel_bin_) ++bin_start_[b + 1];
  for (int b = 0; b < num_beams_; ++b) bin_start_[b + 1] += bin_start_[b];
  sorted_range_.resize(pixel_range_.size());
  std::vector<int> fill(bin_start_.begin(), bin_start_.end() - 1);
  for (size_t i = 0; i < pixel_bin_.size(); ++i) {
    sorted_range_[fill[pixel_bin_[i]]++] = pixel_range_[i];
  }
  const float k = static_cast<float>(options_.range_noise_k);
  const float sigmas = static_cast<float>(options_.surface_window_sigmas);
  for (int b = 0; b < num_beams_; ++b) {
    float* first = sorted_range_.data() + bin_start_[b];
    float* last = sorted_range_.data() + bin_start_[b + 1];
    if (last - first < 2) continue;
    const float r_min = (*best)[b];
    const float limit = r_min + sigmas * k * r_min * r_min;
    float* end = std::partition(first, last, [limit](float r) { return r <= limit; });
    float* mid = first + (end - first) / 2;
    std::nth_element(first, mid, end);
    // The median sits on one of the quantised depth levels (5 cm apart at 4 m for a Kinect):
    // the mean of the pixels within half a window of it, symmetric, averages the levels.
    const float median = *mid, half = 0.5f * (limit - r_min);
    double sum = 0;
    int n = 0;
    for (const float* r = first; r != last; ++r) {
      if (std::abs(*r - median) <= half) sum += *r, ++n;
    }
    (*best)[b] = static_cast<float>(sum / n);
  }
}

}  // namespace depth
}  // namespace sarmap
