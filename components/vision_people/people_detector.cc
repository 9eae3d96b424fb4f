#include "vision_people/people_detector.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <tuple>

#include "vision_people/hog_classifier.h"

namespace sarmap {
namespace vision_people {
namespace {

constexpr double kBelowFloorM = 0.3;  // voxel grid starts this far below the prior floor
constexpr int kPad = 2;  // empty cells around the grid: neighbour search needs no bounds checks

// Membership rising linearly from 0 at `lo` to 1 at `hi`.
double Ramp(double x, double lo, double hi) {
  if (x <= lo) return 0.0;
  if (x >= hi) return 1.0;
  return (x - lo) / (hi - lo);
}
// 1 inside [b, c], linear to 0 at a and d.
double Trapezoid(double x, double a, double b, double c, double d) {
  return std::min(Ramp(x, a, b), 1.0 - Ramp(x, c, d));
}

// A right-handed frame on the floor: x lateral (to the camera's left), y forward (the camera's
// z projected on the floor), z up; origin below the camera.
struct FloorFrame {
  Eigen::Matrix3d R;  // rows: lateral, forward, up (camera -> floor rotation)
  Eigen::Vector3d t;  // floor = R * camera + t
  explicit FloorFrame(const GroundPlane& g) {
    const Eigen::Vector3d up = g.normal;
    Eigen::Vector3d fwd = Eigen::Vector3d::UnitZ() - up.z() * up;
    if (fwd.norm() < 1e-6) fwd = Eigen::Vector3d::UnitY() - up.y() * up;
    fwd.normalize();
    const Eigen::Vector3d lat = fwd.cross(up);  // x = y cross z
    R.row(0) = lat.transpose();
    R.row(1) = fwd.transpose();
    R.row(2) = up.transpose();
    t = R * (g.offset * up);
  }
  Eigen::Vector3d ToFloor(const Eigen::Vector3d& p) const { return R * p + t; }
  Eigen::Vector3d ToCamera(const Eigen::Vector3d& f) const { return R.transpose() * (f - t); }
};

struct UnionFind {
  std::vector<int> parent;
  void Reset(int n) {
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0);
  }
  int Find(int i) {
    while (parent[i] != i) {
      parent[i] = parent[parent[i]];
      i = parent[i];
    }
    return i;
  }
  void Union(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Pixel row of camera-frame point p (NaN behind the camera).
double ProjectV(const PinholeIntrinsics& k, const Eigen::Vector3d& p) {
  return p.z() > 1e-6 ? k.fy * p.y() / p.z() + k.cy : std::numeric_limits<double>::quiet_NaN();
}
double ProjectU(const PinholeIntrinsics& k, const Eigen::Vector3d& p) {
  return p.z() > 1e-6 ? k.fx * p.x() / p.z() + k.cx : std::numeric_limits<double>::quiet_NaN();
}

// Height h at which the vertical line foot + h * up crosses image row v.
double HeightAtRow(const PinholeIntrinsics& k, const Eigen::Vector3d& foot,
                   const Eigen::Vector3d& up, double v) {
  const double a = v - k.cy;
  const double den = k.fy * up.y() - a * up.z();
  if (std::abs(den) < 1e-9) return std::numeric_limits<double>::quiet_NaN();
  return (a * foot.z() - k.fy * foot.y()) / den;
}

double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The body centre behind the centroid of a visible surface (floor frame, camera above the
// origin): moved away from the camera along the floor by (pi/8) * body thickness.
Eigen::Vector3d BodyCentre(const Eigen::Vector3d& centroid_floor, const NoiseOptions& noise) {
  const Eigen::Vector2d xy = centroid_floor.head<2>();
  if (xy.norm() < 1e-6) return centroid_floor;
  Eigen::Vector3d out = centroid_floor;
  out.head<2>() += xy.normalized() * (M_PI / 8) * noise.body_thickness_m;
  return out;
}

// Covariance of a cluster centroid: Kinect depth noise along the ray (sigma = c z^2), pixel
// noise across it, plus the body centre's spread about the visible surface.
Eigen::Matrix3d CentroidCovariance(const Eigen::Vector3d& p, const NoiseOptions& noise, double fx) {
  const double z = std::max(0.1, p.z());
  const Eigen::Vector3d u = p.normalized();
  const double sr = noise.depth_coeff * z * z;
  const double st = z * noise.pixel_sigma / std::max(1.0, fx);
  const double sb2 = noise.body_sigma_m * noise.body_sigma_m;
  const Eigen::Matrix3d along = u * u.transpose();
  return (sr * sr + sb2) * along + (st * st + sb2) * (Eigen::Matrix3d::Identity() - along);
}

// Is the image just below camera-frame point `low` (a cluster's lowest point) filled by
// something at least 0.3 m nearer? Then the cluster's bottom is hidden (a person behind a
// desk or a crate), not floating.
bool HiddenBelow(const RgbdFrame& frame, const Eigen::Vector3d& low) {
  const PinholeIntrinsics& k = frame.intrinsics;
  if (low.z() <= 0.1) return false;
  const int u0 = static_cast<int>(std::lround(k.fx * low.x() / low.z() + k.cx));
  const int v0 = static_cast<int>(std::lround(k.fy * low.y() / low.z() + k.cy));
  const float limit = static_cast<float>(low.z() - 0.3);
  int nearer = 0, seen = 0;
  for (int v = v0 + 2; v <= v0 + 14; v += 3) {
    for (int u = u0 - 6; u <= u0 + 6; u += 3) {
      if (u < 0 || v < 0 || u >= frame.width || v >= frame.height) continue;
      const float z = frame.xyz[3 * (static_cast<size_t>(v) * frame.width + u) + 2];
      if (!std::isfinite(z)) continue;
      ++seen;
      nearer += z < limit;
    }
  }
  return seen >= 5 && nearer * 2 >= seen;
}

}  // namespace

std::string DescribeCandidate(const PersonCandidate& c) {
  auto format = [&c](char* out, size_t size) {
    return snprintf(
        out, size,
        "%s pos (%.2f %.2f %.2f) H %.2f bottom %.2f width %.2f depth %.2f head %.2f/%.2f prom "
        "%.2f areas %.3f/%.3f fill %.2f visible %.2f%s voxels %d | depth %.2f hog %s %.2f conf "
        "%.2f",
        c.accepted ? "PERSON" : "reject", c.position_camera.x(), c.position_camera.y(),
        c.position_camera.z(), c.height_m, c.bottom_m, c.width_m, c.depth_extent_m, c.head_width_m,
        c.shoulder_width_m, c.head_prominence_m, c.head_area_m2, c.shoulder_area_m2, c.fill,
        c.visible_fraction, c.truncated_top ? " (top cut)" : "", c.num_voxels, c.depth_score,
        c.hog_used ? "yes" : "no", c.hog_score, c.confidence);
  };
  std::string line(format(nullptr, 0), '\0');
  format(&line[0], line.size() + 1);
  return line;
}

const char* ColorStateName(ColorState state) {
  switch (state) {
    case ColorState::kNone:
      return "none";
    case ColorState::kUsable:
      return "usable";
    case ColorState::kDark:
      return "dark";
    case ColorState::kLowContrast:
      return "low-contrast";
    case ColorState::kGlare:
      return "glare";
  }
  return "?";
}

void CloudFromDepth(const uint16_t* depth, int width, int height, double unit_m,
                    const PinholeIntrinsics& k, RgbdFrame* frame) {
  frame->width = width;
  frame->height = height;
  frame->intrinsics = k;
  frame->xyz.resize(static_cast<size_t>(width) * height * 3);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const double ifx = 1.0 / k.fx, ify = 1.0 / k.fy;
  for (int v = 0; v < height; ++v) {
    const float yk = static_cast<float>((v - k.cy) * ify);
    for (int u = 0; u < width; ++u) {
      const size_t i = static_cast<size_t>(v) * width + u;
      float* p = &frame->xyz[3 * i];
      const uint16_t d = depth[i];
      if (d == 0) {
        p[0] = p[1] = p[2] = nan;
        continue;
      }
      const float z = static_cast<float>(d * unit_m);
      p[0] = static_cast<float>((u - k.cx) * ifx) * z;
      p[1] = yk * z;
      p[2] = z;
    }
  }
}

namespace {

// ImageStatistics over a width x height region of a larger image with rows of row_stride
// pixels (`rgb` at the region's top-left pixel).
void RegionStatistics(const uint8_t* rgb, int width, int height, int row_stride, int step,
                      double* mean, double* stddev, double* saturated) {
  double s = 0, s2 = 0;
  int64_t n = 0, sat = 0;
  step = std::max(1, step);
  for (int v = 0; v < height; v += step) {
    const uint8_t* row = rgb + static_cast<size_t>(v) * row_stride * 3;
    for (int u = 0; u < width; u += step) {
      const uint8_t* p = row + 3 * u;
      const int grey = (77 * p[0] + 150 * p[1] + 29 * p[2]) >> 8;
      s += grey;
      s2 += grey * grey;
      sat += grey >= 250;
      ++n;
    }
  }
  const double m = n ? s / n : 0.0;
  *mean = m;
  *stddev = n ? std::sqrt(std::max(0.0, s2 / n - m * m)) : 0.0;
  *saturated = n ? static_cast<double>(sat) / n : 0.0;
}

}  // namespace

void ImageStatistics(const uint8_t* rgb, int width, int height, int step, double* mean,
                     double* stddev, double* saturated) {
  RegionStatistics(rgb, width, height, width, step, mean, stddev, saturated);
}

namespace {

// The voxels of `cluster` on walls (and cupboard fronts): vertical planes found on the part
// higher than a person's head (>= 2.0 m above the floor), up to three, by RANSAC
// (deterministic) on lines on the floor: >= 30 of those high voxels within 0.04 m + 2 sigma
// of the range noise, spanning >= 1.2 m along the line; every voxel of the cluster within
// 0.04 m + 3 sigma of the line goes (Kinect's range steps at 4-5 m, 5-7 cm, leave a wall's
// tail beyond 2 sigma, and on a person's head it makes the person too tall). A person standing 0.3
// m in front of a wall at 4 m is joined to it by the range noise (of the floor between them, of the
// mixed pixels at the silhouette); without the wall the person is a cluster again. `lines`: per
// wall a point on it and its normal on the floor, towards the camera.
struct WallLine {
  Eigen::Vector2d point, normal;
};
// Half-width of a wall's band at range z: 0.04 m + `sigmas` sigma of the range noise.
double WallBand(double z, double depth_coeff, double sigmas) {
  return 0.04 + sigmas * depth_coeff * z * z;
}
std::vector<int> WallVoxels(const std::vector<int>& cluster,
                            const std::vector<Eigen::Vector3d>& floor_points,
                            const std::vector<Eigen::Vector3d>& camera_points, double depth_coeff,
                            std::vector<WallLine>* lines) {
  constexpr int kPlanes = 3, kIterations = 60, kMinHighInliers = 30;
  constexpr double kHighM = 2.0, kMinWidthM = 1.2;
  std::vector<int> walls;
  std::vector<int> rest = cluster;
  auto band = [&](int i) { return WallBand(camera_points[i].z(), depth_coeff, 2); };
  uint32_t state = 12345;  // a small LCG: the same voxels give the same walls
  auto next = [&state](size_t n) {
    state = state * 1664525u + 1013904223u;
    return static_cast<size_t>((state >> 8) % n);
  };
  for (int plane = 0; plane < kPlanes; ++plane) {
    std::vector<int> high;
    for (int i : rest) {
      if (floor_points[i].z() >= kHighM) high.push_back(i);
    }
    if (static_cast<int>(high.size()) < kMinHighInliers) break;
    size_t best_count = 0;
    Eigen::Vector2d best_point = Eigen::Vector2d::Zero(), best_normal = Eigen::Vector2d::UnitY();
    for (int it = 0; it < kIterations; ++it) {
      const Eigen::Vector2d a = floor_points[high[next(high.size())]].head<2>();
      const Eigen::Vector2d b = floor_points[high[next(high.size())]].head<2>();
      if ((b - a).norm() < 0.5) continue;
      const Eigen::Vector2d dir = (b - a).normalized();
      const Eigen::Vector2d normal(-dir.y(), dir.x());
      size_t count = 0;
      for (int i : high) count += std::abs(normal.dot(floor_points[i].head<2>() - a)) <= band(i);
      if (count > best_count) {
        best_count = count;
        best_point = a;
        best_normal = normal;
      }
    }
    if (static_cast<int>(best_count) < kMinHighInliers) break;
    const Eigen::Vector2d along(best_normal.y(), -best_normal.x());
    double smin = 1e9, smax = -1e9;
    for (int i : high) {
      const Eigen::Vector2d d = floor_points[i].head<2>() - best_point;
      if (std::abs(best_normal.dot(d)) > band(i)) continue;
      smin = std::min(smin, along.dot(d));
      smax = std::max(smax, along.dot(d));
    }
    if (smax - smin < kMinWidthM) break;
    std::vector<int> outliers;
    for (int i : rest) {
      const Eigen::Vector2d d = floor_points[i].head<2>() - best_point;
      const bool wall =
          std::abs(best_normal.dot(d)) <= WallBand(camera_points[i].z(), depth_coeff, 3);
      (wall ? walls : outliers).push_back(i);
    }
    rest.swap(outliers);
    // The floor frame's origin is below the camera. The noise tail of a wall already found
    // (parallel within 15 degrees, within 0.3 m of it) is no new wall.
    const WallLine line{best_point, best_normal.dot(best_point) > 0 ? -best_normal : best_normal};
    bool seen = false;
    for (const WallLine& w : *lines) {
      seen = seen || (w.normal.dot(line.normal) > std::cos(15 * M_PI / 180) &&
                      std::abs(w.normal.dot(line.point - w.point)) < 0.3);
    }
    if (!seen) lines->push_back(line);
  }
  return walls;
}

// A body lying on the floor, from the floor-frame voxels of one cluster: top height, floor
// contact, length and width along the principal axes of its footprint, relief (spread of the
// highest point per 0.1 m along the body, inner 80 %) and fill; the whole body must be inside
// the image (its length is unknown otherwise).
PersonCandidate DescribeLying(const std::vector<int>& cluster,
                              const std::vector<Eigen::Vector3d>& floor_points,
                              const std::vector<Eigen::Vector3d>& camera_points,
                              const FloorFrame& floor_frame, const RgbdFrame& frame,
                              const DetectorOptions& options) {
  const LyingOptions& lo = options.lying;
  const double vs = options.voxel_size_m;
  PersonCandidate c;
  c.lying = true;
  c.depth_only = true;
  c.num_voxels = static_cast<int>(cluster.size());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double top = -1e9, bottom = 1e9;
  for (int i : cluster) {
    centroid += floor_points[i];
    top = std::max(top, floor_points[i].z());
    bottom = std::min(bottom, floor_points[i].z());
  }
  centroid /= static_cast<double>(cluster.size());
  c.height_m = top;
  c.bottom_m = bottom;
  c.position_camera = floor_frame.ToCamera(BodyCentre(centroid, options.noise));
  c.head_camera = floor_frame.ToCamera(Eigen::Vector3d(centroid.x(), centroid.y(), top));
  // Principal axes of the footprint.
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (int i : cluster) {
    const Eigen::Vector2d d = floor_points[i].head<2>() - centroid.head<2>();
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Eigen::Vector2d along = eig.eigenvectors().col(1), across = eig.eigenvectors().col(0);
  double amin = 1e9, amax = -1e9, cmin = 1e9, cmax = -1e9;
  for (int i : cluster) {
    const Eigen::Vector2d d = floor_points[i].head<2>() - centroid.head<2>();
    amin = std::min(amin, along.dot(d));
    amax = std::max(amax, along.dot(d));
    cmin = std::min(cmin, across.dot(d));
    cmax = std::max(cmax, across.dot(d));
  }
  c.length_m = amax - amin + vs;
  c.width_m = cmax - cmin + vs;
  c.depth_extent_m = c.length_m;
  // Highest point per 0.1 m along the body.
  const double bin = 0.1;
  const int nbins = std::max(1, static_cast<int>((amax - amin) / bin) + 1);
  std::vector<double> profile(nbins, -1.0);
  for (int i : cluster) {
    const int b = std::clamp(
        static_cast<int>((along.dot(floor_points[i].head<2>() - centroid.head<2>()) - amin) / bin),
        0, nbins - 1);
    profile[b] = std::max(profile[b], floor_points[i].z());
  }
  int filled = 0;
  for (double h : profile) filled += h >= 0;
  c.fill = static_cast<double>(filled) / nbins;
  std::vector<double> inner;
  for (int b = nbins / 10; b < nbins - nbins / 10; ++b) {
    if (profile[b] >= 0) inner.push_back(profile[b]);
  }
  if (inner.size() >= 3) {
    std::sort(inner.begin(), inner.end());
    // 10th to 90th percentile: one noisy bin does not make a box a body.
    c.relief_m = inner[inner.size() * 9 / 10] - inner[inner.size() / 10];
  }
  // Inside the image: no voxel of the cluster projects within 3 px of the image border.
  bool inside = true;
  double umin = 1e9, umax = -1e9, vmin = 1e9, vmax = -1e9;
  for (int i : cluster) {
    const Eigen::Vector3d& p = camera_points[i];
    const double u = ProjectU(frame.intrinsics, p), v = ProjectV(frame.intrinsics, p);
    if (!std::isfinite(u) || !std::isfinite(v)) {
      inside = false;
      continue;
    }
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  }
  const double margin = std::max(3, frame.width / 100) +
                        0.5 * vs * frame.intrinsics.fx / std::max(0.5, c.position_camera.z());
  inside = inside && umin > margin && vmin > margin && umax < frame.width - 1 - margin &&
           vmax < frame.height - 1 - margin;
  c.visible_fraction = inside ? 1.0 : 0.0;
  c.box_u_center = 0.5 * (umin + umax);
  c.box_v_top = vmin;
  c.box_v_bottom = vmax;
  const double m_top =
      Trapezoid(top, lo.min_top_m - 0.05, lo.min_top_m, lo.max_top_m, lo.max_top_m + 0.1);
  const double m_bottom = 1.0 - Ramp(bottom, lo.max_bottom_m, lo.max_bottom_m + 0.1);
  const double m_length = Trapezoid(c.length_m, lo.min_length_m - 0.2, lo.min_length_m,
                                    lo.max_length_m, lo.max_length_m + 0.3);
  // Only the near side of a body is seen: its width across the viewing ray is measured, its
  // depth along the ray is not (seen side-on from a low camera, a lying body is a 0.1 m thick
  // strip). The lower bound applies to the part of the width that lies across the ray.
  const Eigen::Vector2d ray_xy = centroid.head<2>().norm() > 1e-6
                                     ? Eigen::Vector2d(centroid.head<2>().normalized())
                                     : Eigen::Vector2d(0, 1);
  const double across_ray = std::abs(across.x() * ray_xy.y() - across.y() * ray_xy.x());
  const double min_width = lo.min_width_m * across_ray;
  const double m_width =
      Trapezoid(c.width_m, 0.7 * min_width, min_width, lo.max_width_m, lo.max_width_m + 0.2);
  const double m_relief = Ramp(c.relief_m, 0.5 * lo.min_relief_m, lo.min_relief_m);
  const double m_fill = Ramp(c.fill, lo.min_fill - 0.2, lo.min_fill);
  c.depth_score = m_top * m_bottom * m_length * m_width * m_relief * m_fill * c.visible_fraction;
  c.supported = m_bottom >= 0.5;
  c.confidence = c.depth_score;
  c.accepted = c.depth_score >= lo.accept;
  c.covariance = CentroidCovariance(c.position_camera, options.noise, frame.intrinsics.fx);
  return c;
}

}  // namespace

// ---------------------------------------------------------------------------------------

// The voxel grid and the per-frame state the stages of Detect share.
struct DetectorWorkspace {
  // Dense voxel grid over the region of interest, in the prior floor frame.
  int nx = 0, ny = 0, nz = 0;
  double x0 = 0, y0 = 0,
         z0 = 0;  // floor-frame coordinates of cell (0,0,0)'s corner (before padding)
  std::vector<int32_t> cell_voxel;  // -1: empty
  // Voxels of the current frame.
  std::vector<int32_t> voxel_cell;
  std::vector<Eigen::Vector3f> sum;  // camera frame
  std::vector<int32_t> count;
  // Per voxel, after the floor refinement.
  std::vector<Eigen::Vector3d> centroid;  // camera frame
  std::vector<Eigen::Vector3d> floor;     // refined floor frame
  std::vector<uint8_t> kept;
  std::vector<int32_t> neighbour_offsets;
  UnionFind uf;
  // The columns of the depth's field of view, as the union of the columns that held depth over
  // the frames seen so far: a registered depth image leaves bands without depth at its sides
  // (the depth camera's field is narrower than the colour camera's), and the floor fills
  // every column the depth sees. Reset when the image size changes. (The top band is not
  // learned: a head within it is usually a person close by, and what is cut there has a flat
  // top.)
  int fov_width = 0, fov_height = 0;
  int fov_umin = 0, fov_umax = -1;

  int64_t Cell(int ix, int iy, int iz) const {
    return (static_cast<int64_t>(iz + kPad) * (ny + 2 * kPad) + (iy + kPad)) * (nx + 2 * kPad) +
           (ix + kPad);
  }
};

namespace {

using Clusters = std::vector<std::vector<int>>;

// Whether the colour image can be used for this frame: its size, and with a colour classifier
// its light, contrast and glare (stats->color_state says which failed).
bool ColorUsable(const RgbdFrame& frame, bool have_hog, const ColorOptions& c,
                 DetectionStats* stats, std::string* err) {
  if (!frame.has_color()) return false;
  const size_t pixels = static_cast<size_t>(frame.width) * frame.height;
  if (frame.rgb.size() != 3 * pixels) {
    *err = "colour image size does not match the depth (" + std::to_string(frame.rgb.size()) +
           " bytes for " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
           "); using depth only";
    return false;
  }
  if (!have_hog) return false;
  double mean, stddev, saturated;
  ImageStatistics(frame.rgb.data(), frame.width, frame.height, 4, &mean, &stddev, &saturated);
  stats->color_mean = mean;
  stats->color_std = stddev;
  if (mean < c.dark_mean) {
    stats->color_state = ColorState::kDark;
  } else if (saturated > c.max_saturated) {
    stats->color_state = ColorState::kGlare;
  } else if (stddev < c.min_contrast) {
    stats->color_state = ColorState::kLowContrast;
  } else {
    stats->color_state = ColorState::kUsable;
    return true;
  }
  return false;
}

// Stage 1b: the voxel grid in the frame of `grid_plane` (the floor found in this frame, else
// the track or the mounting), without flying pixels. Returns the number of finite points.
int Voxelize(const RgbdFrame& frame, const DetectorOptions& o, const GroundPlane& grid_plane,
             DetectorWorkspace& ws) {
  const float inv_vs = static_cast<float>(1.0 / o.voxel_size_m);
  const FloorFrame prior_frame(grid_plane);
  const Eigen::Matrix3f Rf = prior_frame.R.cast<float>();
  const Eigen::Vector3f tf = prior_frame.t.cast<float>();
  const float x0 = static_cast<float>(ws.x0), y0 = static_cast<float>(ws.y0),
              z0 = static_cast<float>(ws.z0);
  const float min_z = static_cast<float>(o.min_range_m);
  ws.voxel_cell.clear();
  ws.sum.clear();
  ws.count.clear();
  int num_points = 0;
  if (ws.fov_width != frame.width || ws.fov_height != frame.height) {
    ws.fov_width = frame.width;
    ws.fov_height = frame.height;
    ws.fov_umin = frame.width;
    ws.fov_umax = -1;
  }
  const int stride = o.pixel_stride;
  const float depth_noise = static_cast<float>(o.noise.depth_coeff);
  for (int v = 0; v < frame.height; v += stride) {
    const float* row = &frame.xyz[static_cast<size_t>(v) * frame.width * 3];
    for (int u = 0; u < frame.width; u += stride) {
      const float* p = row + 3 * u;
      const float z = p[2];
      if (!(z >= min_z) || !std::isfinite(p[0]) || !std::isfinite(p[1])) continue;  // NaN fails
      ++num_points;
      ws.fov_umin = std::min(ws.fov_umin, u);
      ws.fov_umax = std::max(ws.fov_umax, u);
      // Mixed ("flying") pixels at a depth edge lie between the near and the far surface and
      // would join a person to the wall behind: a pixel whose left and right neighbours are one
      // nearer and one farther, both by more than the noise, is dropped. Along columns only:
      // up and down, the floor and a lying body seen at a grazing angle change depth that fast.
      if (u >= 1 && u + 1 < frame.width) {
        const float t = 0.03f + 3.0f * depth_noise * z * z;
        const float a = p[2 - 3], b = p[2 + 3];
        if ((a < z - t && b > z + t) || (a > z + t && b < z - t)) continue;  // NaN: false
      }
      const Eigen::Vector3f pc(p[0], p[1], z);
      const Eigen::Vector3f f = Rf * pc + tf;
      const int ix = static_cast<int>(std::floor((f.x() - x0) * inv_vs));
      const int iy = static_cast<int>(std::floor((f.y() - y0) * inv_vs));
      const int iz = static_cast<int>(std::floor((f.z() - z0) * inv_vs));
      if (ix < 0 || iy < 0 || iz < 0 || ix >= ws.nx || iy >= ws.ny || iz >= ws.nz) continue;
      const int64_t cell = ws.Cell(ix, iy, iz);
      int32_t& vox = ws.cell_voxel[cell];
      if (vox < 0) {
        vox = static_cast<int32_t>(ws.voxel_cell.size());
        ws.voxel_cell.push_back(static_cast<int32_t>(cell));
        ws.sum.push_back(pc);
        ws.count.push_back(1);
      } else {
        ws.sum[vox] += pc;
        ++ws.count[vox];
      }
    }
  }
  return num_points;
}

// Stage 2: the floor polished and tracked; returns the floor this frame uses. The polish is a
// least-squares plane through the voxels near the RANSAC plane, twice with a shrinking band,
// accepted only close to it. Floor candidates must have nothing 0.18-0.30 m above them (cells
// iz+3, iz+4 of their column): the bottom rows of a wall, a cabinet or a leg lie in the band
// too and would tilt the fit.
GroundPlane PolishFloor(const FloorFit& fit, const DetectorOptions& o, const GroundPlane& mounting,
                        int64_t utime, DetectorWorkspace& ws, GroundTracker& tracker,
                        DetectionStats* stats) {
  const int nv = static_cast<int>(ws.voxel_cell.size());
  GroundPlane ground = mounting;
  if (fit.found) {
    const int64_t layer = static_cast<int64_t>(ws.ny + 2 * kPad) * (ws.nx + 2 * kPad);
    const int64_t layers = ws.nz + 2 * kPad;
    ws.kept.assign(nv, 0);  // here: "open above" (floor candidate) flags
    for (int i = 0; i < nv; ++i) {
      const int64_t cell = ws.voxel_cell[i];
      bool open = true;
      for (int k = 3; k <= 4 && open; ++k) {
        if (cell / layer + k < layers) open = ws.cell_voxel[cell + k * layer] < 0;
      }
      ws.kept[i] = open;
    }
    GroundPlane estimate = fit.plane;
    bool ok = true;
    int used = 0;
    for (double band : {o.ground.band_m, 0.5 * o.ground.band_m}) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
      used = 0;
      for (int i = 0; i < nv; ++i) {
        const Eigen::Vector3d& c = ws.centroid[i];
        if (!ws.kept[i] || std::abs(estimate.Height(c)) > band) continue;
        mean += c;
        second += c * c.transpose();
        ++used;
      }
      if (used < o.ground.min_voxels) {
        ok = false;
        break;
      }
      mean /= used;
      const Eigen::Matrix3d cov = second / used - mean * mean.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      // A floor patch is spread in two directions; a strip or a post is not.
      if (eig.eigenvalues()(1) < 0.05 * 0.05) {
        ok = false;
        break;
      }
      Eigen::Vector3d n = eig.eigenvectors().col(0);
      if (n.dot(fit.plane.normal) < 0) n = -n;
      estimate.normal = n;
      estimate.offset = -n.dot(mean);
    }
    stats->num_ground_voxels = used;
    ok = ok && AngleBetweenDeg(estimate, fit.plane) <= o.ground.max_tilt_change_deg &&
         std::abs(estimate.offset - fit.plane.offset) <= o.ground.max_offset_change_m;
    const GroundPlane this_frame = ok ? estimate : fit.plane;
    ground = tracker.Update(&this_frame, utime);
    stats->ground_refined = true;
  } else if (o.ground.refine) {
    // No floor in view (or none plausible): the track, else the mounting file.
    ground = tracker.Update(nullptr, utime);
  }
  return ground;
}

// Stage 3: floor coordinates of every voxel; those within removal_m of the floor (or below it)
// are dropped.
void RemoveFloor(const FloorFrame& floor_frame, double removal_m, DetectorWorkspace& ws) {
  const int nv = static_cast<int>(ws.voxel_cell.size());
  ws.floor.resize(nv);
  ws.kept.assign(nv, 0);
  for (int i = 0; i < nv; ++i) {
    ws.floor[i] = floor_frame.ToFloor(ws.centroid[i]);
    ws.kept[i] = ws.floor[i].z() >= removal_m;
  }
}

// Euclidean clustering of `voxels` (kept ones): union of voxels whose centroids are closer than
// `tolerance_m` (<= 2 voxels, so the +-2 cell neighbourhood holds every such pair). Clusters
// come in the order of their first voxel in `voxels`.
Clusters ConnectedVoxels(const std::vector<int>& voxels, double tolerance_m,
                         DetectorWorkspace& ws) {
  const int nv = static_cast<int>(ws.voxel_cell.size());
  const double tol2 = tolerance_m * tolerance_m;
  ws.uf.Reset(nv);
  for (int i : voxels) {
    const int64_t cell = ws.voxel_cell[i];
    for (int32_t off : ws.neighbour_offsets) {
      const int32_t j = ws.cell_voxel[cell + off];
      if (j < 0 || !ws.kept[j]) continue;
      if ((ws.centroid[i] - ws.centroid[j]).squaredNorm() < tol2) ws.uf.Union(i, j);
    }
  }
  Clusters clusters;
  std::vector<int> cluster_of_root(nv, -1);
  for (int i : voxels) {
    int& c = cluster_of_root[ws.uf.Find(i)];
    if (c < 0) {
      c = static_cast<int>(clusters.size());
      clusters.emplace_back();
    }
    clusters[c].push_back(i);
  }
  return clusters;
}

// Stage 4b: a cluster too large or too tall for a person is searched for walls; what is left
// without them is clustered again (a person in front of a wall). Only against a floor seen in
// this frame: a floor carried over may be tilted, and so would be the walls in its frame (their
// lower parts would stand in front of the band).
void SplitWalls(const DetectorOptions& o, DetectorWorkspace& ws, Clusters* clusters_out) {
  Clusters& clusters = *clusters_out;
  // Pieces are appended and searched too (a corner: two walls); each search removes voxels.
  for (size_t c = 0; c < clusters.size(); ++c) {
    double top = -std::numeric_limits<double>::infinity();
    for (int i : clusters[c]) top = std::max(top, ws.floor[i].z());
    if (static_cast<int>(clusters[c].size()) <= o.max_cluster_voxels &&
        top <= o.candidate_max_height_m) {
      continue;
    }
    std::vector<WallLine> planes;
    const std::vector<int> walls =
        WallVoxels(clusters[c], ws.floor, ws.centroid, o.noise.depth_coeff, &planes);
    if (walls.empty()) continue;
    for (int i : walls) ws.kept[i] = 0;
    std::vector<int>& rest = clusters[c];
    rest.erase(std::remove_if(rest.begin(), rest.end(), [&](int i) { return !ws.kept[i]; }),
               rest.end());
    Clusters pieces = ConnectedVoxels(rest, o.cluster_tolerance_m, ws);
    rest.clear();
    // What stands clear in front of every wall (its centroid >= 0.15 m, about half a body's
    // depth, in front of the wall's 2-sigma band) is kept; the rest is part of the walls or
    // stands against them (a recess, a door frame, a chair pushed to the wall).
    for (auto& piece : pieces) {
      Eigen::Vector2d centre = Eigen::Vector2d::Zero();
      double range = 0;
      for (int i : piece) {
        centre += ws.floor[i].head<2>();
        range += ws.centroid[i].z();
      }
      centre /= static_cast<double>(piece.size());
      range /= static_cast<double>(piece.size());
      const double clear = WallBand(range, o.noise.depth_coeff, 2) + 0.15;
      bool in_front = true;
      for (const WallLine& w : planes)
        in_front = in_front && w.normal.dot(centre - w.point) >= clear;
      if (in_front) clusters.push_back(std::move(piece));
    }
  }
}

// Stage 5: clusters whose ground-plane centroids are closer than merge_distance_m are one
// (pieces of one person split by occlusion).
void MergeNearClusters(double merge_distance_m, const DetectorWorkspace& ws,
                       Clusters* clusters_out) {
  Clusters& clusters = *clusters_out;
  {
    const int nc = static_cast<int>(clusters.size());
    std::vector<Eigen::Vector2d> centre(nc, Eigen::Vector2d::Zero());
    for (int c = 0; c < nc; ++c) {
      for (int i : clusters[c]) centre[c] += ws.floor[i].head<2>();
      centre[c] /= static_cast<double>(clusters[c].size());
    }
    UnionFind merge;
    merge.Reset(nc);
    for (int a = 0; a < nc; ++a) {
      for (int b = a + 1; b < nc; ++b) {
        if ((centre[a] - centre[b]).norm() < merge_distance_m) merge.Union(a, b);
      }
    }
    std::vector<std::vector<int>> merged(nc);
    for (int c = 0; c < nc; ++c) {
      auto& into = merged[merge.Find(c)];
      into.insert(into.end(), clusters[c].begin(), clusters[c].end());
    }
    clusters.clear();
    for (auto& m : merged) {
      if (!m.empty()) clusters.push_back(std::move(m));
    }
  }
}

// The horizontal axis across the viewing ray to a cluster's centre, and the
// cluster's extent along it.
struct SpanAcrossRay {
  Eigen::Vector2d across;
  double min, max;
};
SpanAcrossRay SpanAcrossViewingRay(const std::vector<int>& cluster, const DetectorWorkspace& ws) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (int i : cluster) centre += ws.floor[i].head<2>();
  centre /= static_cast<double>(cluster.size());
  const Eigen::Vector2d ray = centre.norm() > 1e-6 ? centre.normalized() : Eigen::Vector2d(0, 1);
  SpanAcrossRay span;
  span.across = Eigen::Vector2d(-ray.y(), ray.x());
  span.min = std::numeric_limits<double>::infinity();
  span.max = -span.min;
  for (int i : cluster) {
    const double s = span.across.dot(ws.floor[i].head<2>());
    span.min = std::min(span.min, s);
    span.max = std::max(span.max, s);
  }
  return span;
}

// Stage 5b: an arm held up above the head is no head. On the lateral height profile (highest
// point per 6 cm bin across the viewing ray) it is a spike at most two bins wide 0.1 m below
// its top, beside a lower, wider maximum (the head) within 0.5 m. The arm's bins above the
// head's shoulder level are removed, so the head is the top again and the other shoulder
// shows its prominence.
void RemoveRaisedArms(const DetectorOptions& o, const DetectorWorkspace& ws, Clusters* clusters) {
  const double vs = o.voxel_size_m;
  for (auto& cluster : *clusters) {
    for (int pass = 0; pass < 2; ++pass) {  // both arms
      const SpanAcrossRay span = SpanAcrossViewingRay(cluster, ws);
      const Eigen::Vector2d across = span.across;
      const double smin = span.min, smax = span.max;
      const int nbins = static_cast<int>((smax - smin) / vs) + 1;
      if (nbins < 4) break;
      std::vector<double> profile(nbins, -1.0);
      auto bin_of = [&](int i) {
        return std::clamp(static_cast<int>((across.dot(ws.floor[i].head<2>()) - smin) / vs), 0,
                          nbins - 1);
      };
      for (int i : cluster) profile[bin_of(i)] = std::max(profile[bin_of(i)], ws.floor[i].z());
      const int peak =
          static_cast<int>(std::max_element(profile.begin(), profile.end()) - profile.begin());
      const double top = profile[peak];
      if (top < o.candidate_min_height_m) break;
      // Width of a maximum at `drop` below its height: contiguous bins at or above that.
      // (stopping at the bins [skip_lo, skip_hi]).
      int skip_lo = nbins, skip_hi = -1;
      auto extent = [&](int b, double level, int* lo, int* hi) {
        *lo = *hi = b;
        while (*lo > 0 && profile[*lo - 1] >= level && !(*lo - 1 >= skip_lo && *lo - 1 <= skip_hi))
          --*lo;
        while (*hi + 1 < nbins && profile[*hi + 1] >= level &&
               !(*hi + 1 >= skip_lo && *hi + 1 <= skip_hi))
          ++*hi;
      };
      int lo, hi;
      extent(peak, top - 0.1, &lo, &hi);
      skip_lo = lo;
      skip_hi = hi;
      if (hi - lo + 1 > 2) break;
      // The head: the highest bin outside the spike within 0.5 m, lower by 0.1 m or more
      // and at least three bins wide 0.1 m below its own top.
      const int reach = static_cast<int>(0.5 / vs);
      int head = -1;
      for (int b = std::max(0, lo - reach); b <= std::min(nbins - 1, hi + reach); ++b) {
        if (b >= lo && b <= hi) continue;
        if (profile[b] < 0 || profile[b] > top - 0.1) continue;
        if (head < 0 || profile[b] > profile[head]) head = b;
      }
      if (head < 0 || profile[head] < top - 0.7) break;
      int hlo, hhi;
      extent(head, profile[head] - 0.1, &hlo, &hhi);
      if (hhi - hlo + 1 < 3) break;
      const double cut = profile[head] - o.shape.shoulder_drop_m;
      cluster.erase(std::remove_if(cluster.begin(), cluster.end(),
                                   [&](int i) {
                                     const int b = bin_of(i);
                                     return b >= lo && b <= hi && ws.floor[i].z() > cut;
                                   }),
                    cluster.end());
    }
  }
}

// Stage 6: each upright cluster split at its heads, the local maxima of a height map along
// the axis across the viewing ray. `parent_of`: the cluster each part came from;
// `heads_in_cluster`: how many heads each cluster has.
struct HeadParts {
  Clusters parts;
  std::vector<size_t> parent_of;
  std::vector<int> heads_in_cluster;
};
HeadParts SplitAtHeads(const Clusters& clusters, const DetectorOptions& o,
                       const DetectorWorkspace& ws) {
  const double vs = o.voxel_size_m;
  HeadParts split;
  split.heads_in_cluster.assign(clusters.size(), 0);
  Clusters& subclusters = split.parts;
  std::vector<size_t>& parent_of = split.parent_of;
  std::vector<int>& heads_in_cluster = split.heads_in_cluster;
  const double head_d2 = o.min_head_distance_m * o.min_head_distance_m;
  for (const auto& cluster : clusters) {
    double cluster_top = -std::numeric_limits<double>::infinity();
    for (int i : cluster) cluster_top = std::max(cluster_top, ws.floor[i].z());
    if (cluster_top < o.candidate_min_height_m) continue;  // lying-body test instead
    const SpanAcrossRay span = SpanAcrossViewingRay(cluster, ws);
    const Eigen::Vector2d across = span.across;
    const double smin = span.min, smax = span.max;
    const int nbins = static_cast<int>((smax - smin) / vs) + 1;
    std::vector<int> top(nbins, -1);
    for (int i : cluster) {
      const int b =
          std::min(nbins - 1, static_cast<int>((across.dot(ws.floor[i].head<2>()) - smin) / vs));
      if (top[b] < 0 || ws.floor[i].z() > ws.floor[top[b]].z()) top[b] = i;
    }
    auto height = [&](int b) {
      return b < 0 || b >= nbins || top[b] < 0 ? -std::numeric_limits<double>::infinity()
                                               : ws.floor[top[b]].z();
    };
    // Local maxima (a plateau counts once, at its centre): (voxel, bin).
    std::vector<std::pair<int, int>> maxima;
    for (int b = 0; b < nbins; ++b) {
      if (top[b] < 0 || !(height(b) > height(b - 1))) continue;
      int e = b;
      while (e + 1 < nbins && height(e + 1) == height(b)) ++e;
      if (height(e + 1) < height(b)) maxima.emplace_back(top[(b + e) / 2], (b + e) / 2);
      b = e;
    }
    std::sort(maxima.begin(), maxima.end(),
              [&](const std::pair<int, int>& a, const std::pair<int, int>& b) {
                return ws.floor[a.first].z() > ws.floor[b.first].z();
              });
    // A maximum is a new head when it is at least min_head_distance from every higher head
    // and the height map dips by min_head_dip between them (a neck and shoulders, or a gap);
    // range noise on a flat top (a box, a cupboard) makes maxima without such a dip.
    std::vector<int> heads;
    std::vector<int> head_bins;
    for (const auto& [m, bm] : maxima) {
      bool separate = true;
      for (size_t k = 0; k < heads.size() && separate; ++k) {
        separate = (ws.floor[m].head<2>() - ws.floor[heads[k]].head<2>()).squaredNorm() >= head_d2;
        double low = std::numeric_limits<double>::infinity();
        for (int b = std::min(bm, head_bins[k]) + 1; b < std::max(bm, head_bins[k]); ++b)
          low = std::min(low, height(b));
        separate = separate && ws.floor[m].z() - low >= o.min_head_dip_m;
      }
      if (separate) {
        heads.push_back(m);
        head_bins.push_back(bm);
      }
    }
    heads_in_cluster[&cluster - clusters.data()] = static_cast<int>(heads.size());
    std::vector<std::vector<int>> parts(heads.size());
    for (int i : cluster) {
      for (size_t h = 0; h < heads.size(); ++h) {
        if ((ws.floor[i].head<2>() - ws.floor[heads[h]].head<2>()).squaredNorm() < head_d2) {
          parts[h].push_back(i);
          break;
        }
      }
    }
    for (auto& p : parts) {
      if (static_cast<int>(p.size()) >= o.min_subcluster_voxels) {
        subclusters.push_back(std::move(p));
        parent_of.push_back(static_cast<size_t>(&cluster - clusters.data()));
      }
    }
  }

  return split;
}

// What the depth shape score needs of an upright candidate beside its PersonCandidate fields.
struct UprightShape {
  double area_ratio = 1;       // head / head-and-shoulders floor footprint
  double visible_lo_m = 0;     // lowest height above the floor inside the image
  bool bottom_hidden = false;  // something nearer fills the image below its lowest point
};

// Stage 7: the shape of one upright part (`parent`: its whole cluster, `single_head`: the
// cluster's only head). False when its top is outside the candidate heights.
bool DescribeUpright(const std::vector<int>& part, const std::vector<int>& parent, bool single_head,
                     const RgbdFrame& frame, const FloorFrame& floor_frame,
                     const GroundPlane& ground, const DetectorOptions& o,
                     const DetectorWorkspace& ws, PersonCandidate* out, UprightShape* shape) {
  const double vs = o.voxel_size_m;
  const PinholeIntrinsics& K = frame.intrinsics;
  const DepthShapeOptions& so = o.shape;
  PersonCandidate c;
  c.num_voxels = static_cast<int>(part.size());
  Eigen::Vector3d centroid_floor = Eigen::Vector3d::Zero();
  int top_voxel = part.front();
  double bottom = std::numeric_limits<double>::infinity();
  for (int i : part) {
    centroid_floor += ws.floor[i];
    if (ws.floor[i].z() > ws.floor[top_voxel].z()) top_voxel = i;
    bottom = std::min(bottom, ws.floor[i].z());
  }
  centroid_floor /= static_cast<double>(part.size());
  c.height_m = ws.floor[top_voxel].z();
  if (c.height_m < o.candidate_min_height_m || c.height_m > o.candidate_max_height_m) return false;
  // The only head of its cluster: the whole cluster is this person, and its lowest point
  // is the person's (a sitting person's shins are more than the head radius forward).
  if (single_head) {
    for (int i : parent) bottom = std::min(bottom, ws.floor[i].z());
  }
  c.bottom_m = bottom;
  c.position_camera = floor_frame.ToCamera(BodyCentre(centroid_floor, o.noise));
  const Eigen::Vector2d ground_xy = centroid_floor.head<2>();
  const Eigen::Vector2d ray =
      ground_xy.norm() > 1e-6 ? ground_xy.normalized() : Eigen::Vector2d(0, 1);
  const Eigen::Vector2d across(-ray.y(), ray.x());
  const Eigen::Vector3d foot_floor(ground_xy.x(), ground_xy.y(), 0.0);
  const Eigen::Vector3d foot = floor_frame.ToCamera(foot_floor);
  c.head_camera = floor_frame.ToCamera(Eigen::Vector3d(ground_xy.x(), ground_xy.y(), c.height_m));

  // Shape: torso width, extent along the ray, lateral height profile, vertical fill.
  const double H = c.height_m;
  double tmin = 1e9, tmax = -1e9, rmin = 1e9, rmax = -1e9, smin = 1e9, smax = -1e9;
  for (int i : part) {
    const Eigen::Vector2d d = ws.floor[i].head<2>() - ground_xy;
    const double s = across.dot(d), r = ray.dot(d), z = ws.floor[i].z();
    smin = std::min(smin, s);
    smax = std::max(smax, s);
    rmin = std::min(rmin, r);
    rmax = std::max(rmax, r);
    if (z >= 0.5 * H && z <= 0.8 * H) {
      tmin = std::min(tmin, s);
      tmax = std::max(tmax, s);
    }
  }
  c.width_m = tmax >= tmin ? tmax - tmin + vs : 0.0;
  c.depth_extent_m = rmax - rmin + vs;
  // Footprints on the floor (6 cm cells) of the head (points within head_drop of the top)
  // and of head + shoulders (within shoulder_drop): a person's shoulders stick out beside
  // the head from every side; the top edge of a wall, door or cupboard does not.
  const int nslices = static_cast<int>(H / vs) + 1;
  std::vector<uint8_t> slice(nslices, 0);
  constexpr int kFoot = 32;
  uint8_t head_cells[kFoot][kFoot] = {}, shoulder_cells[kFoot][kFoot] = {};
  int head_area = 0, shoulder_area = 0;
  for (int i : part) {
    const Eigen::Vector2d d = ws.floor[i].head<2>() - ground_xy;
    const int cx = std::clamp(static_cast<int>(std::floor(d.x() / vs)) + kFoot / 2, 0, kFoot - 1);
    const int cy = std::clamp(static_cast<int>(std::floor(d.y() / vs)) + kFoot / 2, 0, kFoot - 1);
    const double z = ws.floor[i].z();
    if (z >= H - so.head_drop_m && !head_cells[cx][cy]) {
      head_cells[cx][cy] = 1;
      ++head_area;
    }
    if (z >= H - so.shoulder_drop_m && !shoulder_cells[cx][cy]) {
      shoulder_cells[cx][cy] = 1;
      ++shoulder_area;
    }
    const int s = std::clamp(static_cast<int>(z / vs), 0, nslices - 1);
    slice[s] = 1;
  }
  c.head_area_m2 = head_area * vs * vs;
  c.shoulder_area_m2 = shoulder_area * vs * vs;
  // Lateral height profile (6 cm bins across the viewing ray, highest point per bin):
  // head bins reach within head_drop of the top, head-and-shoulder bins within
  // shoulder_drop. Unlike the footprint it does not smear with range noise.
  {
    const int nbins = static_cast<int>((smax - smin) / vs) + 1;
    std::vector<double> profile(nbins, -1.0);
    for (int i : part) {
      const int b =
          std::clamp(static_cast<int>((across.dot(ws.floor[i].head<2>() - ground_xy) - smin) / vs),
                     0, nbins - 1);
      profile[b] = std::max(profile[b], ws.floor[i].z());
    }
    int head_bins = 0, shoulder_bins = 0;
    for (double h : profile) {
      head_bins += h >= H - so.head_drop_m;
      shoulder_bins += h >= H - so.shoulder_drop_m;
    }
    c.head_width_m = head_bins * vs;
    c.shoulder_width_m = shoulder_bins * vs;
  }

  // What of the head-to-floor span is inside the image.
  const double v_top = ProjectV(K, c.head_camera);
  const double v_foot = ProjectV(K, foot);
  c.box_u_center = ProjectU(K, c.head_camera);
  c.box_v_top = v_top;
  c.box_v_bottom = v_foot;
  double visible_lo = 0.0, visible_hi = H;
  if (std::isfinite(v_foot) && v_foot > frame.height - 1) {
    const double h = HeightAtRow(K, foot, ground.normal, frame.height - 1);
    if (std::isfinite(h)) visible_lo = std::clamp(h, 0.0, H);
  }
  if (std::isfinite(v_top) && v_top < 0) {
    const double h = HeightAtRow(K, foot, ground.normal, 0);
    if (std::isfinite(h)) visible_hi = std::clamp(h, 0.0, H);
  }
  if (!std::isfinite(v_foot) || !std::isfinite(v_top)) visible_hi = visible_lo;
  c.visible_fraction = H > 0 ? std::max(0.0, visible_hi - visible_lo) / H : 0.0;
  // Fill: occupied 6 cm slices between the lowest visible height above the floor removal
  // band and the top.
  const int s0 =
      std::clamp(static_cast<int>(std::max(visible_lo, o.ground.removal_m) / vs) + 1, 0, nslices);
  int occupied = 0, slices = 0;
  for (int s = s0; s < nslices; ++s) {
    occupied += slice[s];
    ++slices;
  }
  c.fill = slices > 0 ? static_cast<double>(occupied) / slices : 0.0;

  // Where the sub-cluster meets the image border its outline is the image's, not the
  // object's: the top may go on above the field of view, and a wall or cupboard whose top is
  // cut by a side border looks like a narrow upright body with a step at its top. Only the
  // head (points within head_drop of the top) counts at the sides: a person whose arm or
  // shoulder leaves the image is still judged by the head. The side borders are those of the
  // depth's field of view (fov_umin/umax); the margin adds half a voxel's image size (voxel
  // centroids lie inside the object's outline).
  {
    double umin = 1e9, umax = -1e9, vmin = 1e9;
    bool finite = true;
    for (int i : part) {
      const double u = ProjectU(K, ws.centroid[i]), v = ProjectV(K, ws.centroid[i]);
      if (!std::isfinite(u) || !std::isfinite(v)) {
        finite = false;
        continue;
      }
      vmin = std::min(vmin, v);
      if (ws.floor[i].z() < H - so.head_drop_m) continue;
      umin = std::min(umin, u);
      umax = std::max(umax, u);
    }
    const double margin =
        std::max(2, frame.height / 48) + 0.5 * vs * K.fx / std::max(0.5, c.position_camera.z());
    c.truncated_top = !finite || vmin < margin;
    c.truncated_side = !finite || umin < ws.fov_umin + margin || umax > ws.fov_umax - margin;
  }

  // Head prominence: how far the top stands above everything at least head_radius away
  // from it on the floor (a person's shoulders, chest or back: 0.2-0.3 m below the top;
  // the top edge of a box, wall or cupboard: ~0).
  // The head centre is the mean of the points within 0.1 m of the top (robust to range
  // noise); with nothing outside the head radius there are no shoulders: prominence 0.
  Eigen::Vector2d top_xy = Eigen::Vector2d::Zero();
  int top_n = 0;
  for (int i : part) {
    if (ws.floor[i].z() >= H - 0.1) {
      top_xy += ws.floor[i].head<2>();
      ++top_n;
    }
  }
  top_xy /= std::max(1, top_n);
  // With a single head in its cluster, the ring is searched in the whole cluster: the
  // 0.3 m cut around the top can leave a box edge looking like a lone peak. With several
  // heads (people side by side) only the sub-cluster, so a neighbour's shoulder does not
  // count.
  // The head region is an ellipse on the floor: head_radius_m across the viewing ray and
  // head_radius_m + head_depth_m along it, because the visible head surface reaches back
  // along the ray (a head seen obliquely shows its side, ~0.2 m deep) and the range noise
  // (sigma = c z^2) spreads it further; across the ray the shoulders stick out.
  // Seen side-on, a sitting person's shoulders lie along the ray, inside the ellipse, and the
  // highest point outside it is the lap, in the lower half of the body: for a top at sitting
  // height with such a point, the shoulders are looked for beyond head_radius_m in every
  // direction. Anything else beside the head more than max_head_prominence_m below it is
  // neither lap nor shoulders.
  double around = -1.0, around_circle = -1.0;
  const double inv_a2 = 1.0 / (so.head_radius_m * so.head_radius_m);
  const double inv_b2 = 1.0 / std::pow(so.head_radius_m + so.head_depth_m, 2);
  const double outer2 = std::pow(so.head_radius_m + o.min_head_distance_m, 2);
  for (int i : single_head ? parent : part) {
    const Eigen::Vector2d d = ws.floor[i].head<2>() - top_xy;
    if (d.squaredNorm() > outer2) continue;
    const double s = across.dot(d), r = ray.dot(d);
    if (s * s * inv_a2 + r * r * inv_b2 >= 1.0) around = std::max(around, ws.floor[i].z());
    if (d.squaredNorm() * inv_a2 >= 1.0) around_circle = std::max(around_circle, ws.floor[i].z());
  }
  if (around >= 0 && H <= so.max_sitting_height_m && around < 0.5 * H &&
      H - around > so.max_head_prominence_m)
    around = around_circle;
  c.head_prominence_m = around < 0 ? 0.0 : H - around;
  shape->area_ratio = shoulder_area > 0 ? static_cast<double>(head_area) / shoulder_area : 1.0;
  shape->visible_lo_m = visible_lo;
  // What is below the lowest point, when the feet are not on the floor: hidden by something
  // nearer (a person behind a desk), or nothing (floating).
  int low_voxel = part.front();
  for (int i : part) {
    if (ws.floor[i].z() < ws.floor[low_voxel].z()) low_voxel = i;
  }
  shape->bottom_hidden = HiddenBelow(frame, ws.centroid[low_voxel]);
  *out = c;
  return true;
}

// Stage 7a: the depth shape score of an upright candidate, a fuzzy AND (product) of
// memberships; `*loose_score`: height, shape and support alone (occlusion and truncation
// allowed), for the fusion with colour. Sets c->depth_score and c->supported.
void ScoreUpright(const UprightShape& shape, const DepthShapeOptions& so, PersonCandidate* c,
                  double* loose_score) {
  const double H = c->height_m;
  const double m_height = Trapezoid(H, so.min_height_m - so.height_margin_m, so.min_height_m,
                                    so.max_height_m, so.max_height_m + so.height_margin_m);
  const double m_width = Trapezoid(c->width_m, 0.6 * so.min_width_m, so.min_width_m, so.max_width_m,
                                   1.3 * so.max_width_m);
  const double m_depth =
      1.0 - Ramp(c->depth_extent_m, so.max_depth_extent_m, so.max_depth_extent_m + 0.3);
  // The head stands above the shoulders, and its floor footprint is smaller than that of
  // head and shoulders (a vertical surface has the same footprint at every height).
  const double m_head =
      Ramp(c->head_prominence_m, so.min_head_prominence_m - 0.06, so.min_head_prominence_m) *
      (1.0 - Ramp(c->head_prominence_m, so.max_head_prominence_m, so.max_head_prominence_m + 0.1)) *
      (1.0 - Ramp(shape.area_ratio, so.max_head_to_shoulder, 1.0)) *
      (1.0 - Ramp(c->head_width_m, so.max_head_width_m, so.max_head_width_m + 0.15));
  const double m_fill = Ramp(c->fill, so.min_fill - 0.2, so.min_fill);
  const double bottom_limit = std::max(so.max_bottom_m, shape.visible_lo_m + 0.2);
  const double m_bottom = 1.0 - Ramp(c->bottom_m, bottom_limit, bottom_limit + 0.3);
  const double m_visible =
      c->truncated_top || c->truncated_side
          ? 0.0
          : Ramp(c->visible_fraction, so.min_visible_fraction - 0.2, so.min_visible_fraction);
  const double body = m_width * m_depth * m_head;
  c->depth_score = m_height * m_bottom * m_visible * m_fill * body;
  // With colour, occlusion and truncation are allowed, but a person stands on something: the
  // feet reach the floor, or what is below the cluster is hidden by something nearer (and
  // then the head and shoulders must be clear: a monitor on a desk has none).
  double m_support = m_bottom;
  if (m_support < 1.0 && shape.bottom_hidden) m_support = std::max(m_support, m_head);
  c->supported = m_support >= 0.5;
  *loose_score = m_height * body * m_support;
}

// Stage 7b: the decision. With a usable colour patch, HOG fused with the loose depth score;
// else the depth score alone.
void Classify(double loose_score, bool color_ok, const RgbdFrame& frame, const HogClassifier* hog,
              const DetectorOptions& o, PersonCandidate* c_out) {
  PersonCandidate& c = *c_out;
  const DepthShapeOptions& so = o.shape;
  const ColorOptions& co = o.color;
  const double v_top = c.box_v_top, v_foot = c.box_v_bottom;
  // Colour: HOG on the patch, unless the patch itself is too dark or flat.
  bool patch_ok = color_ok && std::isfinite(c.box_u_center) && std::isfinite(v_top) &&
                  std::isfinite(v_foot) && v_foot > v_top;
  if (patch_ok) {
    const double person_px = v_foot - v_top;
    const int x0p =
        std::clamp(static_cast<int>(c.box_u_center - person_px / 3), 0, frame.width - 1);
    const int x1p =
        std::clamp(static_cast<int>(c.box_u_center + person_px / 3), 0, frame.width - 1);
    const int y0p = std::clamp(static_cast<int>(v_top), 0, frame.height - 1);
    const int y1p = std::clamp(static_cast<int>(v_foot), 0, frame.height - 1);
    if (x1p - x0p < 4 || y1p - y0p < 8) {
      patch_ok = false;
    } else {
      const int sub_w = x1p - x0p + 1, sub_h = y1p - y0p + 1;
      double mean, stddev, sat;
      RegionStatistics(&frame.rgb[(static_cast<size_t>(y0p) * frame.width + x0p) * 3], sub_w,
                       sub_h, frame.width, std::max(1, std::min(sub_w, sub_h) / 32), &mean,
                       &stddev, &sat);
      patch_ok = mean >= co.dark_mean && stddev >= co.min_contrast && sat <= co.max_saturated;
    }
  }
  if (patch_ok) {
    // Fusion: confidence = w p_hog + (1 - w) loose_score, accepted at co.accept, so a
    // candidate the depth shape supports needs only a weak colour cue (with loose_score 1:
    // p_hog >= 1/6, an SVM margin of -1.6) and HOG vetoes only when it is sure. The HOG
    // score that decides is p_needed's; HOG is skipped when no score could accept, and the
    // window search around the theoretical box (scale and offset errors of the box: range
    // noise, a person not upright) runs only when the centre window falls short. The
    // decision equals that of a full search; the confidence of an accepted candidate is
    // then a lower bound.
    const double w = co.color_weight;
    const double p_needed = w > 0 ? (co.accept - (1.0 - w) * loose_score) / w : 0.0;
    if (loose_score < co.min_depth_score || p_needed >= 1.0) {
      c.confidence = (1.0 - w) * loose_score;  // colour cue not evaluated: counted as 0
      c.accepted = false;
    } else {
      const double hog_needed =
          p_needed <= 0.0 ? -std::numeric_limits<double>::infinity()
                          : co.hog_threshold + co.hog_scale * std::log(p_needed / (1.0 - p_needed));
      c.hog_used = true;
      c.hog_score =
          hog->Score(frame.rgb.data(), frame.width, frame.height, c.box_u_center, v_top, v_foot, 0);
      if (c.hog_score < hog_needed && co.search_steps > 0) {
        c.hog_score =
            std::max(c.hog_score, hog->Score(frame.rgb.data(), frame.width, frame.height,
                                             c.box_u_center, v_top, v_foot, co.search_steps));
      }
      const double p_hog = Logistic((c.hog_score - co.hog_threshold) / co.hog_scale);
      c.confidence = w * p_hog + (1.0 - w) * loose_score;
      c.accepted = c.confidence >= co.accept;
    }
  } else {
    c.depth_only = true;
    c.confidence = c.depth_score;
    c.accepted = c.depth_score >= so.accept;
  }
}

}  // namespace

PeopleDetector::PeopleDetector(const DetectorOptions& options, const GroundPlane& mounting_ground,
                               std::shared_ptr<const HogClassifier> hog)
    : options_(options),
      mounting_(mounting_ground),
      tracker_(options.ground, mounting_ground),
      hog_(std::move(hog)),
      ws_(std::make_unique<DetectorWorkspace>()) {
  common::ValidateOptions(options_);
  const double v = options_.voxel_size_m;
  ws_->x0 = -options_.max_lateral_m;
  ws_->y0 = -0.5;
  ws_->z0 = -kBelowFloorM;
  ws_->nx = static_cast<int>(std::ceil(2 * options_.max_lateral_m / v));
  ws_->ny = static_cast<int>(std::ceil((options_.max_range_m + 0.5) / v));
  ws_->nz = static_cast<int>(std::ceil((options_.top_cut_m + kBelowFloorM) / v));
  const size_t cells =
      static_cast<size_t>(ws_->nx + 2 * kPad) * (ws_->ny + 2 * kPad) * (ws_->nz + 2 * kPad);
  ws_->cell_voxel.assign(cells, -1);
  // Half of the +-2 neighbourhood (lexicographically positive offsets): each pair once.
  for (int dz = -2; dz <= 2; ++dz) {
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        if (std::make_tuple(dz, dy, dx) <= std::make_tuple(0, 0, 0)) continue;
        ws_->neighbour_offsets.push_back(static_cast<int32_t>(
            (static_cast<int64_t>(dz) * (ws_->ny + 2 * kPad) + dy) * (ws_->nx + 2 * kPad) + dx));
      }
    }
  }
}

PeopleDetector::~PeopleDetector() = default;

void PeopleDetector::ResetGround() { tracker_.Reset(); }

DetectionResult PeopleDetector::Detect(const RgbdFrame& frame, std::string* error) {
  DetectionResult result;
  result.ground = tracker_.has_track() ? tracker_.tracked() : mounting_;
  std::string local_error;
  std::string& err = error ? *error : local_error;
  err.clear();
  const size_t pixels = static_cast<size_t>(std::max(0, frame.width)) * std::max(0, frame.height);
  if (frame.width <= 0 || frame.height <= 0 || pixels == 0) {
    err = "empty frame";
    return result;
  }
  if (frame.xyz.size() != 3 * pixels) {
    err = "cloud has " + std::to_string(frame.xyz.size() / 3) + " points for a " +
          std::to_string(frame.width) + "x" + std::to_string(frame.height) + " frame";
    return result;
  }
  const bool color_ok = ColorUsable(frame, hog_ != nullptr, options_.color, &result.stats, &err);

  DetectorWorkspace& ws = *ws_;
  const DetectorOptions& o = options_;

  // 1. Floor from the data: RANSAC over a sample of the cloud with the tracked and the
  // configured floor as extra hypotheses (ground_estimator.h); then the voxel grid in the
  // frame of that floor.
  FloorFit fit;
  if (o.ground.refine) {
    std::vector<GroundPlane> hypotheses;
    if (tracker_.has_track()) hypotheses.push_back(tracker_.tracked());
    hypotheses.push_back(mounting_);
    fit = FitFloor(frame.xyz.data(), frame.width, frame.height, o.min_range_m, o.max_range_m,
                   o.ground, hypotheses);
    result.stats.num_ground_points = fit.inliers;
  }
  const int num_points = Voxelize(frame, o, fit.found ? fit.plane : result.ground, ws);
  result.stats.num_points = num_points;
  const int nv = static_cast<int>(ws.voxel_cell.size());
  result.stats.num_voxels = nv;
  // The grid is cleared at the end of this function through this guard, whatever happens.
  struct ClearGrid {
    DetectorWorkspace* ws;
    ~ClearGrid() {
      for (int32_t c : ws->voxel_cell) ws->cell_voxel[c] = -1;
    }
  } clear_grid{&ws};
  if (num_points == 0) {
    if (err.empty()) err = "no finite depth in the frame";
    return result;
  }
  ws.centroid.resize(nv);
  for (int i = 0; i < nv; ++i)
    ws.centroid[i] = (ws.sum[i] / static_cast<float>(ws.count[i])).cast<double>();

  // 2. Floor polish and track.
  const GroundPlane ground =
      PolishFloor(fit, o, mounting_, frame.utime, ws, tracker_, &result.stats);
  result.stats.ground_reset = o.ground.refine && tracker_.last_update_reset();
  result.stats.ground_held_off = o.ground.refine && tracker_.last_update_held_off();
  result.stats.mounting_mismatch = tracker_.mismatch();
  result.camera = MountingFromGround(ground);
  result.ground = ground;
  const FloorFrame floor_frame(ground);

  // 3. Remove the floor (and what is below it).
  RemoveFloor(floor_frame, o.ground.removal_m, ws);

  // 4. Euclidean clustering of what is left; 4b. walls split off.
  std::vector<int> kept;
  for (int i = 0; i < nv; ++i)
    if (ws.kept[i]) kept.push_back(i);
  Clusters clusters = ConnectedVoxels(kept, o.cluster_tolerance_m, ws);
  if (o.split_walls && fit.found) SplitWalls(o, ws, &clusters);
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                [&](const std::vector<int>& c) {
                                  return static_cast<int>(c.size()) < o.min_cluster_voxels ||
                                         static_cast<int>(c.size()) > o.max_cluster_voxels;
                                }),
                 clusters.end());

  // 5. Merge clusters that are close on the floor; 5b. raised arms off.
  MergeNearClusters(o.merge_distance_m, ws, &clusters);
  result.stats.num_clusters = static_cast<int>(clusters.size());

  RemoveRaisedArms(o, ws, &clusters);

  // 6. Low clusters go to the lying-body test, the others are split at their heads.
  for (const auto& cluster : clusters) {
    double top = -std::numeric_limits<double>::infinity();
    for (int i : cluster) top = std::max(top, ws.floor[i].z());
    if (top >= o.candidate_min_height_m || !o.lying.enabled || top > o.lying.max_top_m + 0.1)
      continue;
    PersonCandidate c = DescribeLying(cluster, ws.floor, ws.centroid, floor_frame, frame, o);
    ++result.stats.num_candidates;
    (c.accepted ? result.people : result.rejected).push_back(c);
  }
  const HeadParts split = SplitAtHeads(clusters, o, ws);

  // 7. Describe and classify each part.
  for (size_t sub = 0; sub < split.parts.size(); ++sub) {
    const size_t parent = split.parent_of[sub];
    PersonCandidate c;
    UprightShape shape;
    if (!DescribeUpright(split.parts[sub], clusters[parent], split.heads_in_cluster[parent] == 1,
                         frame, floor_frame, ground, o, ws, &c, &shape)) {
      continue;
    }
    double loose_score = 0;
    ScoreUpright(shape, o.shape, &c, &loose_score);
    Classify(loose_score, color_ok, frame, hog_.get(), o, &c);
    c.covariance = CentroidCovariance(c.position_camera, o.noise, frame.intrinsics.fx);

    ++result.stats.num_candidates;
    (c.accepted ? result.people : result.rejected).push_back(c);
  }
  return result;
}

std::shared_ptr<const HogClassifier> MakeHogClassifier(const ColorOptions& options) {
  if (options.hog == "opencv") return MakeOpenCvHogClassifier();
  if (options.hog == "pcl") return MakePclHogClassifier(options.pcl_svm_file);
  return nullptr;
}

}  // namespace vision_people
}  // namespace sarmap
