#include "vision_people/ground_estimator.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace sarmap {
namespace vision_people {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kDepthNoise = 0.0015;  // Kinect v1: sigma_z = c z^2 (Khoshelham & Elberink 2012)

// Does the plane put the camera where a robot can carry it?
bool Plausible(const GroundPlane& g, const GroundOptions& o) {
  if (g.offset < o.min_camera_height_m || g.offset > o.max_camera_height_m) return false;
  const CameraMounting m = MountingFromGround(g);
  return std::abs(m.tilt_down_rad) <= o.max_tilt_deg * kDeg &&
         std::abs(m.roll_rad) <= o.max_roll_deg * kDeg;
}

struct Score {
  int inliers = 0;
  int below = 0;
  int value() const { return inliers - below; }
};

Score Evaluate(const GroundPlane& g, const std::vector<Eigen::Vector3f>& pts,
               const GroundOptions& o) {
  Score s;
  const Eigen::Vector3f n = g.normal.cast<float>();
  const float d = static_cast<float>(g.offset);
  const float in0 = static_cast<float>(o.inlier_m), below0 = static_cast<float>(o.below_m);
  const float c = static_cast<float>(kDepthNoise);
  for (const Eigen::Vector3f& p : pts) {
    const float h = n.dot(p) + d;
    const float sigma = c * p.z() * p.z();
    if (std::abs(h) <= in0 + 2 * sigma) {
      ++s.inliers;
    } else if (h < -(below0 + 3 * sigma)) {
      ++s.below;
    }
  }
  return s;
}

// Weighted least squares of the height over the plane through the points within the
// inlier band of `g` (three passes, the band shrinking to 0.7 of itself). Heights, not total
// least squares: the depth noise of far points lies along their rays, nearly parallel to the
// floor, and would tilt a PCA plane towards the camera. Each point is weighted by the inverse
// variance of its height (the depth noise projected on the normal). False when too few
// points or not spread in two directions (a strip is no floor).
// `up[i]`: the sample point one sample row above point i (-1: none); a point whose upper
// neighbour rises steeply from it (a wall, a cabinet, a leg) is no floor, although its bottom
// rows lie within the inlier band.
bool Refine(const std::vector<Eigen::Vector3f>& pts, const std::vector<int>& up,
            const GroundOptions& o, int min_points, GroundPlane* g, int* used_out) {
  for (int pass = 0; pass < 3; ++pass) {
    const Eigen::Vector3d n = g->normal;
    Eigen::Vector3d es = n.cross(Eigen::Vector3d::UnitZ());
    if (es.norm() < 1e-6) es = n.cross(Eigen::Vector3d::UnitX());
    es.normalize();
    const Eigen::Vector3d et = n.cross(es);
    const Eigen::Vector3d origin = -g->offset * n;
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    Eigen::Vector2d mean_st = Eigen::Vector2d::Zero();
    Eigen::Matrix2d second_st = Eigen::Matrix2d::Zero();
    double wsum = 0;
    int used = 0;
    const double scale = pass == 0 ? 1.0 : 0.7;
    for (size_t i = 0; i < pts.size(); ++i) {
      const Eigen::Vector3d p = pts[i].cast<double>();
      const double sigma = kDepthNoise * p.z() * p.z();
      const double h = g->Height(p);
      if (std::abs(h) > scale * (o.inlier_m + 2 * sigma)) continue;
      if (up[i] >= 0) {
        const Eigen::Vector3d q = pts[up[i]].cast<double>();
        const double rise = g->Height(q) - h;
        const double run = ((q - p) - (q - p).dot(n) * n).norm();
        if (rise > 0.5 * run + 0.02) continue;
      }
      const double sigma_h = sigma * std::abs(n.dot(p.normalized()));
      const double w = 1.0 / (0.005 * 0.005 + sigma_h * sigma_h);
      const Eigen::Vector3d d = p - origin;
      const Eigen::Vector3d x(es.dot(d), et.dot(d), 1.0);
      A += w * x * x.transpose();
      b += w * h * x;
      mean_st += x.head<2>();
      second_st += x.head<2>() * x.head<2>().transpose();
      wsum += w;
      ++used;
    }
    *used_out = used;
    if (used < std::max(3, min_points)) return false;
    mean_st /= used;
    const Eigen::Matrix2d cov = second_st / used - mean_st * mean_st.transpose();
    if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvalues()(0) < 0.05 * 0.05)
      return false;
    const Eigen::Vector3d abc = A.ldlt().solve(b);
    if (!abc.allFinite()) return false;
    // h = a s + b t + c  ->  (n - a es - b et) . (p - origin) - c = 0.
    const Eigen::Vector3d m = n - abc(0) * es - abc(1) * et;
    const double k = m.norm();
    g->normal = m / k;
    g->offset = (g->offset - abc(2)) / k;
  }
  return true;
}

}  // namespace

GroundPlane GroundPlane::FromCoefficients(const Eigen::Vector4d& abcd) {
  GroundPlane g;
  const double n = abcd.head<3>().norm();
  g.normal = abcd.head<3>() / n;
  g.offset = abcd(3) / n;
  // The camera is above the floor: its height (the offset) must be positive.
  if (g.offset < 0) {
    g.normal = -g.normal;
    g.offset = -g.offset;
  }
  return g;
}

GroundPlane GroundFromMounting(const Eigen::Matrix3d& base_R_camera,
                               const Eigen::Vector3d& base_t_camera) {
  // Floor: e_z . (R p + t) = 0  ->  (R^T e_z) . p + t_z = 0.
  GroundPlane g;
  g.normal = base_R_camera.transpose() * Eigen::Vector3d::UnitZ();
  g.offset = base_t_camera.z();
  return g;
}

CameraMounting MountingFromGround(const GroundPlane& g) {
  // Camera optical frame: z forward, x right, y down; the floor's up direction is `normal`.
  CameraMounting m;
  m.height_m = g.offset;
  m.tilt_down_rad = std::asin(std::clamp(-g.normal.z(), -1.0, 1.0));
  m.roll_rad = std::atan2(g.normal.x(), -g.normal.y());
  return m;
}

GroundPlane GroundFromCameraMounting(const CameraMounting& m) {
  // Up in the camera frame: level camera (0, -1, 0), tilted down by t: the optical axis z has
  // a component -sin(t) along up; rolled by r: up leans towards +x.
  const double ct = std::cos(m.tilt_down_rad), st = std::sin(m.tilt_down_rad);
  const double cr = std::cos(m.roll_rad), sr = std::sin(m.roll_rad);
  GroundPlane g;
  g.normal = Eigen::Vector3d(ct * sr, -ct * cr, -st);
  g.offset = m.height_m;
  return g;
}

double AngleBetweenDeg(const GroundPlane& a, const GroundPlane& b) {
  return std::acos(std::clamp(a.normal.dot(b.normal), -1.0, 1.0)) / kDeg;
}

FloorFit FitFloor(const float* xyz, int width, int height, double min_range_m, double max_range_m,
                  const GroundOptions& o, const std::vector<GroundPlane>& hypotheses) {
  FloorFit fit;
  std::vector<Eigen::Vector3f> pts;
  std::vector<int> up;  // index of the sample point one sample row above, or -1
  const int stride = std::max(1, o.sample_stride_px);
  const int cols = (width - stride / 2 + stride - 1) / stride;
  pts.reserve(static_cast<size_t>(cols) * (height / stride + 1));
  std::vector<int> previous_row(cols, -1), this_row(cols, -1);
  // Rows offset by half a stride: the sample does not line up with the image border.
  for (int v = stride / 2; v < height; v += stride) {
    const float* row = xyz + static_cast<size_t>(v) * width * 3;
    for (int k = 0, u = stride / 2; u < width && k < cols; u += stride, ++k) {
      const float* p = row + 3 * u;
      this_row[k] = -1;
      if (!(p[2] >= min_range_m && p[2] <= max_range_m) || !std::isfinite(p[0]) ||
          !std::isfinite(p[1]))
        continue;
      this_row[k] = static_cast<int>(pts.size());
      up.push_back(previous_row[k]);
      pts.emplace_back(p[0], p[1], p[2]);
    }
    std::swap(previous_row, this_row);
  }
  fit.sampled = static_cast<int>(pts.size());
  const int min_points = std::max(20, static_cast<int>(o.min_inlier_fraction * pts.size()));
  if (static_cast<int>(pts.size()) < min_points) return fit;
  // Hypotheses are scored on an evenly spread subset.
  std::vector<Eigen::Vector3f> eval;
  const size_t step = std::max<size_t>(1, pts.size() / std::max(1, o.ransac_eval_points));
  for (size_t i = 0; i < pts.size(); i += step) eval.push_back(pts[i]);

  GroundPlane best;
  int best_score = std::numeric_limits<int>::min();
  bool have = false;
  auto consider = [&](const GroundPlane& g) {
    if (!Plausible(g, o)) return;
    const Score s = Evaluate(g, eval, o);
    if (s.value() > best_score) {
      best_score = s.value();
      best = g;
      have = true;
    }
  };
  for (const GroundPlane& g : hypotheses) consider(g);
  // Half the hypotheses from three points anywhere, half from three points close together in
  // the image (a floor seen in a few rows is a small fraction of the cloud, but locally it is
  // all floor).
  std::mt19937 rng(12345);  // fixed: the same frame gives the same floor
  std::uniform_int_distribution<size_t> pick(0, pts.size() - 1);
  std::uniform_int_distribution<int> near(-static_cast<int>(pts.size() / 12),
                                          static_cast<int>(pts.size() / 12));
  auto nearby = [&](size_t i) {
    return static_cast<size_t>(std::clamp<int64_t>(static_cast<int64_t>(i) + near(rng), 0,
                                                   static_cast<int64_t>(pts.size()) - 1));
  };
  for (int it = 0; it < o.ransac_iterations; ++it) {
    const size_t ia = pick(rng);
    const bool local = it % 2 == 1;
    const Eigen::Vector3d a = pts[ia].cast<double>();
    const Eigen::Vector3d b = pts[local ? nearby(ia) : pick(rng)].cast<double>();
    const Eigen::Vector3d c = pts[local ? nearby(ia) : pick(rng)].cast<double>();
    Eigen::Vector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    if (len < 1e-6) continue;
    n /= len;
    if (n.y() > 0) n = -n;  // up is -y in the camera frame (within the tilt limit)
    GroundPlane g;
    g.normal = n;
    g.offset = -n.dot(a);
    consider(g);
  }
  const int eval_min = std::max(10, static_cast<int>(o.min_inlier_fraction * eval.size()));
  // Enough floor, and (almost) nothing seen through it.
  if (!have) return fit;
  const Score s = Evaluate(best, eval, o);
  if (s.inliers < eval_min || s.below > 0.1 * s.inliers) return fit;
  GroundPlane refined = best;
  int used = 0;
  if (!Refine(pts, up, o, min_points, &refined, &used) || !Plausible(refined, o)) return fit;
  fit.found = true;
  fit.plane = refined;
  fit.inliers = used;
  return fit;
}

GroundTracker::GroundTracker(const GroundOptions& options, const GroundPlane& mounting)
    : options_(options), mounting_(mounting), tracked_(mounting) {}

void GroundTracker::Reset() {
  frames_ = 0;
  tracked_ = mounting_;
  jumping_ = false;
}

bool GroundTracker::Apart(const GroundPlane& a, const GroundPlane& b) const {
  return std::abs(a.offset - b.offset) > options_.reset_height_m ||
         AngleBetweenDeg(a, b) > options_.reset_angle_deg;
}

GroundPlane GroundTracker::Update(const GroundPlane* fit, int64_t utime) {
  last_reset_ = false;
  last_held_off_ = false;
  if (frames_ > 0 && (utime < last_utime_ || (utime - last_utime_) * 1e-6 > options_.reset_gap_s)) {
    Reset();
    last_reset_ = true;
    ++resets_;
  }
  last_utime_ = utime;
  if (!fit) {
    // No floor in view (a wall, the sky of a ceiling): the camera is rigidly mounted, so the
    // track (or, without one, the mounting file) is the best guess.
    return frames_ > 0 ? tracked_ : mounting_;
  }
  if (frames_ > 0 && Apart(*fit, tracked_)) {
    // A camera on a robot does not move on its mount: a jump away from the mounting file is
    // something else filling the view until it has lasted, unless the track is still young (the
    // mounting file may be wrong) or the jump comes back to the mounting file.
    if (established() && options_.reset_confirm_s > 0 && Apart(*fit, mounting_)) {
      if (!jumping_ || Apart(*fit, jump_)) jump_since_utime_ = utime;
      jumping_ = true;
      jump_ = *fit;
      if ((utime - jump_since_utime_) * 1e-6 < options_.reset_confirm_s) {
        last_held_off_ = true;
        ++held_off_;
        return tracked_;
      }
    }
    frames_ = 0;
    last_reset_ = true;
    ++resets_;
  }
  jumping_ = false;
  if (frames_ == 0) {
    tracked_ = *fit;
  } else {
    const double w = options_.smoothing;
    tracked_.normal = ((1 - w) * tracked_.normal + w * fit->normal).normalized();
    tracked_.offset = (1 - w) * tracked_.offset + w * fit->offset;
  }
  ++frames_;
  return tracked_;
}

bool GroundTracker::mismatch() const {
  return established() &&
         (std::abs(tracked_.offset - mounting_.offset) > options_.mismatch_height_m ||
          AngleBetweenDeg(tracked_, mounting_) > options_.mismatch_angle_deg);
}

}  // namespace vision_people
}  // namespace sarmap
