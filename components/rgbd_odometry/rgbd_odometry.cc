#include "rgbd_odometry/rgbd_odometry.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <sstream>

#include "common/transform.h"

namespace sarmap {
namespace rgbd_odometry {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

double AngleOf(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.linear()).angle(); }

// The motion `m` scaled by k along its twist (approximately: the rotation angle and the
// translation are scaled independently, which is exact for k in {0, 1} and close for small
// motions).
Eigen::Isometry3d ScaleMotion(const Eigen::Isometry3d& m, double k) {
  const Eigen::AngleAxisd aa(m.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() * k, aa.axis()).toRotationMatrix();
  out.translation() = m.translation() * k;
  return out;
}

std::string Percent(double f) {
  std::ostringstream s;
  s.precision(3);
  s << 100.0 * f << " %";
  return s.str();
}

// A frame converted for OpenCV: depth in metres (invalid NaN, or 0 for fast_icp), grey image,
// validity mask, at the processing scale.
struct Prepared {
  cv::Mat depth;  // CV_32FC1
  cv::Mat gray;   // CV_8UC1 or empty
  cv::Mat mask;   // CV_8UC1, 255 valid
  cv::Matx33d camera;
  double valid_fraction = 0;
};

}  // namespace

const char* TrackingStatusName(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kInitialised:
      return "initialised";
    case TrackingStatus::kTracking:
      return "tracking";
    case TrackingStatus::kReinitialised:
      return "reinitialised";
    case TrackingStatus::kLost:
      return "lost";
    case TrackingStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

Eigen::Isometry3d RigFromOptical() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = common::BodyFromOpticalRotation();
  return t;
}

Eigen::Isometry3d RigPoseFromOpticalPose(const Eigen::Isometry3d& world_from_optical) {
  const Eigen::Isometry3d rig_from_optical = RigFromOptical();
  return rig_from_optical * world_from_optical * rig_from_optical.inverse();
}

Eigen::Matrix<double, 6, 6> PoseCovariance(const PoseCovarianceOptions& o,
                                           const RgbdOdometryResult& r) {
  const double reloc = std::sqrt(static_cast<double>(std::max<int64_t>(0, r.relocalisations)));
  const double sp = o.position_sigma_m + o.position_drift * r.distance_m;
  const double sp_total = std::hypot(sp, o.relocalisation_sigma_m * reloc);
  const double sr = (o.rotation_sigma_deg + o.rotation_drift_deg_per_m * r.distance_m) * kDegToRad +
                    o.rotation_drift * r.rotation_rad;
  const double sr_total = std::hypot(sr, o.relocalisation_sigma_deg * kDegToRad * reloc);
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 3; ++i) cov(i, i) = sp_total * sp_total;
  for (int i = 3; i < 6; ++i) cov(i, i) = sr_total * sr_total;
  return cov;
}

struct RgbdOdometry::Impl {
  RgbdOdometryOptions options;
  RgbdOdometryStats stats;
  cv::Ptr<cv::rgbd::Odometry> odometry;
  cv::Matx33d odometry_camera;  // the camera `odometry` was made for
  cv::Size odometry_size;

  bool started = false;  // a frame has been accepted (world exists)
  int64_t last_utime = 0;
  double last_dt_s = 0;
  // Keyframe (empty when there is none: first frame, or after a loss).
  cv::Ptr<cv::rgbd::OdometryFrame> keyframe;
  cv::Mat keyframe_depth;  // NaN-invalid depth for the overlap check
  Eigen::Isometry3d world_from_keyframe = Eigen::Isometry3d::Identity();  // optical
  Eigen::Isometry3d world_from_last = Eigen::Isometry3d::Identity();      // optical
  Eigen::Isometry3d last_motion = Eigen::Isometry3d::Identity();  // optical, previous_from_last
  double distance_m = 0, rotation_rad = 0;

  bool NeedsImage() const { return options.method == "rgbd" || options.method == "rgbd_icp"; }

  std::string CheckInput(const RgbdFrame& f) const {
    std::ostringstream e;
    if (f.width <= 0 || f.height <= 0) {
      e << "empty frame (" << f.width << "x" << f.height << ")";
    } else if (f.width > 8192 || f.height > 8192) {
      e << "frame too large (" << f.width << "x" << f.height << ")";
    } else if (f.depth.size() != static_cast<size_t>(f.width) * f.height) {
      e << "depth has " << f.depth.size() << " values, expected " << f.width << "x" << f.height;
    } else if (!(std::isfinite(f.depth_unit_m) && f.depth_unit_m > 0 && f.depth_unit_m < 1)) {
      e << "depth unit " << f.depth_unit_m << " m is not in (0, 1)";
    } else if (!(std::isfinite(f.camera.fx) && std::isfinite(f.camera.fy) && f.camera.fx > 0 &&
                 f.camera.fy > 0 && std::isfinite(f.camera.cx) && std::isfinite(f.camera.cy))) {
      e << "bad intrinsics fx " << f.camera.fx << " fy " << f.camera.fy << " cx " << f.camera.cx
        << " cy " << f.camera.cy;
    } else if (!f.image.empty() && f.image_channels != 1 && f.image_channels != 3) {
      e << "image has " << f.image_channels << " channels (1 grey or 3 RGB)";
    } else if (!f.image.empty() &&
               f.image.size() != static_cast<size_t>(f.width) * f.height * f.image_channels) {
      e << "image has " << f.image.size() << " bytes, expected " << f.width << "x" << f.height
        << "x" << f.image_channels << " (same size as the depth)";
    } else if (f.image.empty() && NeedsImage()) {
      e << "method " << options.method << " needs an image";
    } else if (f.has_motion_prior && !f.previous_from_rig_prior.matrix().allFinite()) {
      e << "motion prior is not finite";
    } else if (started && f.utime <= last_utime) {
      e << "time " << f.utime << " us is not after the previous frame's " << last_utime;
    }
    return e.str();
  }

  Prepared Prepare(const RgbdFrame& f) const {
    Prepared p;
    const double s = options.image_scale;
    const bool fast = options.method == "fast_icp";
    const float invalid = fast ? 0.f : std::numeric_limits<float>::quiet_NaN();
    cv::Mat depth(f.height, f.width, CV_32FC1);
    const float unit = static_cast<float>(f.depth_unit_m);
    const float lo = static_cast<float>(options.min_depth_m);
    const float hi = static_cast<float>(options.max_depth_m);
    for (int r = 0; r < f.height; ++r) {
      const uint16_t* in = f.depth.data() + static_cast<size_t>(r) * f.width;
      float* out = depth.ptr<float>(r);
      for (int c = 0; c < f.width; ++c) {
        const float z = in[c] * unit;
        out[c] = (in[c] != 0 && z >= lo && z <= hi) ? z : invalid;
      }
    }
    cv::Mat gray;
    if (!f.image.empty()) {
      const cv::Mat img(f.height, f.width, f.image_channels == 1 ? CV_8UC1 : CV_8UC3,
                        const_cast<uint8_t*>(f.image.data()));
      if (f.image_channels == 3) {
        cv::cvtColor(img, gray, cv::COLOR_RGB2GRAY);
      } else {
        gray = img.clone();
      }
    }
    if (s != 1.0) {
      const cv::Size size(std::max(1, static_cast<int>(std::lround(f.width * s))),
                          std::max(1, static_cast<int>(std::lround(f.height * s))));
      cv::Mat small;
      // Nearest: never blend a valid depth with an invalid one or across an edge.
      cv::resize(depth, small, size, 0, 0, cv::INTER_NEAREST);
      depth = small;
      if (!gray.empty()) {
        cv::Mat g;
        cv::resize(gray, g, size, 0, 0, cv::INTER_AREA);
        gray = g;
      }
    }
    // Valid where the depth is a number in range (NaN != NaN; 0 for fast_icp).
    p.mask = (depth == depth) & (depth > 0);
    p.valid_fraction = static_cast<double>(cv::countNonZero(p.mask)) / depth.total();
    p.depth = depth;
    p.gray = gray;
    const double sx = static_cast<double>(depth.cols) / f.width;
    const double sy = static_cast<double>(depth.rows) / f.height;
    // Pixel centres: u' + 0.5 = (u + 0.5) * scale.
    p.camera = cv::Matx33d(f.camera.fx * sx, 0, (f.camera.cx + 0.5) * sx - 0.5,  //
                           0, f.camera.fy * sy, (f.camera.cy + 0.5) * sy - 0.5,  //
                           0, 0, 1);
    return p;
  }

  void MakeOdometry(const cv::Matx33d& camera, const cv::Size& size) {
    const cv::Mat k(camera);
    const std::vector<int>& iters = options.iteration_counts;
    const std::vector<float> grads(iters.size(),
                                   static_cast<float>(options.min_gradient_magnitude));
    const float lo = static_cast<float>(options.min_depth_m);
    const float hi = static_cast<float>(options.max_depth_m);
    const float diff = static_cast<float>(options.max_depth_diff_m);
    const float part = static_cast<float>(options.max_points_part);
    // OpenCV's own motion test (on the change from the initial guess) is disabled: the
    // plausibility checks below give clearer reasons.
    const double no_limit_m = 1e3, no_limit_deg = 180;
    if (options.method == "rgbd") {
      auto o = cv::rgbd::RgbdOdometry::create(k, lo, hi, diff, iters, grads, part);
      o->setMaxTranslation(no_limit_m);
      o->setMaxRotation(no_limit_deg);
      odometry = o;
    } else if (options.method == "icp") {
      auto o = cv::rgbd::ICPOdometry::create(k, lo, hi, diff, part, iters);
      o->setMaxTranslation(no_limit_m);
      o->setMaxRotation(no_limit_deg);
      odometry = o;
    } else if (options.method == "rgbd_icp") {
      auto o = cv::rgbd::RgbdICPOdometry::create(k, lo, hi, diff, part, iters, grads);
      o->setMaxTranslation(no_limit_m);
      o->setMaxRotation(no_limit_deg);
      odometry = o;
    } else {
      odometry = cv::rgbd::FastICPOdometry::create(k, diff, static_cast<float>(30 * kDegToRad),
                                                   0.04f, 4.5f, 7, iters);
    }
    odometry_camera = camera;
    odometry_size = size;
  }

  cv::Ptr<cv::rgbd::OdometryFrame> MakeFrame(const Prepared& p, int cache) const {
    cv::Ptr<cv::rgbd::OdometryFrame> f =
        cv::rgbd::OdometryFrame::create(NeedsImage() ? p.gray : cv::Mat(), p.depth, p.mask);
    odometry->prepareFrameCache(f, cache);
    return f;
  }

  // Fraction of the current frame's valid points (every `step`-th pixel) that, moved by
  // keyframe_from_current, project into the keyframe onto a depth within max_depth_diff_m.
  double Overlap(const Prepared& p, const Eigen::Isometry3d& keyframe_from_current) const {
    const cv::Mat& kd = keyframe_depth;
    const int step = std::max(1, p.depth.cols / 160);
    const cv::Matx33d& k = p.camera;
    const Eigen::Matrix3d r = keyframe_from_current.linear();
    const Eigen::Vector3d t = keyframe_from_current.translation();
    int64_t valid = 0, agree = 0;
    for (int v = 0; v < p.depth.rows; v += step) {
      const float* row = p.depth.ptr<float>(v);
      const uint8_t* mrow = p.mask.ptr<uint8_t>(v);
      for (int u = 0; u < p.depth.cols; u += step) {
        if (!mrow[u]) continue;
        ++valid;
        const double z = row[u];
        const Eigen::Vector3d pc((u - k(0, 2)) / k(0, 0) * z, (v - k(1, 2)) / k(1, 1) * z, z);
        const Eigen::Vector3d pk = r * pc + t;
        if (pk.z() <= 0) continue;
        const int uk = static_cast<int>(std::lround(k(0, 0) * pk.x() / pk.z() + k(0, 2)));
        const int vk = static_cast<int>(std::lround(k(1, 1) * pk.y() / pk.z() + k(1, 2)));
        if (uk < 0 || vk < 0 || uk >= kd.cols || vk >= kd.rows) continue;
        const float zk = kd.at<float>(vk, uk);
        if (zk > 0 && std::abs(zk - pk.z()) <= options.max_depth_diff_m) ++agree;
      }
    }
    return valid > 0 ? static_cast<double>(agree) / valid : 0.0;
  }

  // `frame` (already prepared as a source, or null) gets the destination cache too.
  void SetKeyframe(const Prepared& p, cv::Ptr<cv::rgbd::OdometryFrame> frame,
                   const Eigen::Isometry3d& world_from_optical) {
    if (frame) {
      odometry->prepareFrameCache(frame, cv::rgbd::OdometryFrame::CACHE_DST);
      keyframe = frame;
    } else {
      keyframe = MakeFrame(p, cv::rgbd::OdometryFrame::CACHE_ALL);
    }
    keyframe_depth = p.depth;
    world_from_keyframe = world_from_optical;
    ++stats.keyframes;
  }

  void Fill(RgbdOdometryResult* r) const {
    r->world_from_optical = world_from_last;
    r->world_from_rig = RigPoseFromOpticalPose(world_from_last);
    r->distance_m = distance_m;
    r->rotation_rad = rotation_rad;
    r->relocalisations = stats.relocalisations;
  }

  RgbdOdometryResult Process(const RgbdFrame& f) {
    RgbdOdometryResult r;
    r.utime = f.utime;
    ++stats.frames;
    const std::string bad = CheckInput(f);
    if (!bad.empty()) {
      ++stats.invalid;
      r.status = TrackingStatus::kInvalidInput;
      r.message = bad;
      Fill(&r);
      return r;
    }
    const double dt_s = started ? 1e-6 * (f.utime - last_utime) : 0.0;
    const bool first = stats.keyframes == 0;  // no world yet
    started = true;
    last_utime = f.utime;

    const Prepared p = Prepare(f);
    r.valid_depth_fraction = p.valid_fraction;
    auto lose = [&](const std::string& why) {
      ++stats.lost;
      keyframe.release();
      keyframe_depth.release();
      last_motion.setIdentity();
      last_dt_s = 0;
      r.status = TrackingStatus::kLost;
      r.message = why;
      Fill(&r);
    };
    if (p.valid_fraction < options.min_valid_depth_fraction) {
      lose("only " + Percent(p.valid_fraction) + " of the depth is valid (min " +
           Percent(options.min_valid_depth_fraction) + ")");
      return r;
    }
    try {
      const cv::Size size(p.depth.cols, p.depth.rows);
      if (!odometry || size != odometry_size || p.camera != odometry_camera) {
        const bool had = static_cast<bool>(odometry);
        MakeOdometry(p.camera, size);
        if (had) keyframe.release();  // a new camera: start again from the held pose
      }
      if (!keyframe) {
        SetKeyframe(p, nullptr, world_from_last);
        last_motion.setIdentity();
        last_dt_s = 0;
        r.keyframe = true;
        if (first) {
          r.status = TrackingStatus::kInitialised;
        } else {
          r.status = TrackingStatus::kReinitialised;
          ++stats.relocalisations;
        }
        Fill(&r);
        return r;
      }
      // Initial guess: the frame's motion prior, else the last motion scaled to this time step
      // (times velocity_prior_gain).
      Eigen::Isometry3d predicted;
      if (f.has_motion_prior) {
        const Eigen::Isometry3d rig_from_optical = RigFromOptical();
        predicted = rig_from_optical.inverse() * f.previous_from_rig_prior * rig_from_optical;
      } else {
        const double k = last_dt_s > 0 ? std::clamp(dt_s / last_dt_s, 0.0, 4.0) : 1.0;
        predicted = ScaleMotion(last_motion, k * options.velocity_prior_gain);
      }
      const Eigen::Isometry3d keyframe_from_last = world_from_keyframe.inverse() * world_from_last;
      const Eigen::Isometry3d guess = keyframe_from_last * predicted;
      cv::Mat init;
      cv::eigen2cv(Eigen::Matrix4d(guess.matrix()), init);
      cv::Ptr<cv::rgbd::OdometryFrame> current = MakeFrame(p, cv::rgbd::OdometryFrame::CACHE_SRC);
      cv::Mat rt;
      // Rt maps points of the source (current) frame into the destination (keyframe) frame.
      const bool converged = odometry->compute(current, keyframe, rt, init);
      if (!converged || rt.empty()) {
        lose("OpenCV " + options.method + " odometry failed (too few correspondences)");
        return r;
      }
      Eigen::Matrix4d m;
      cv::cv2eigen(rt, m);
      if (!m.allFinite()) {
        lose("OpenCV " + options.method + " odometry returned a non-finite motion");
        return r;
      }
      Eigen::Isometry3d keyframe_from_current = Eigen::Isometry3d::Identity();
      // Re-orthonormalise (the exponential map is computed in float in places).
      keyframe_from_current.linear() =
          Eigen::Quaterniond(m.topLeftCorner<3, 3>()).normalized().toRotationMatrix();
      keyframe_from_current.translation() = m.topRightCorner<3, 1>();
      const Eigen::Isometry3d world_from_current = world_from_keyframe * keyframe_from_current;
      const Eigen::Isometry3d motion = world_from_last.inverse() * world_from_current;
      const double step_m = motion.translation().norm();
      const double step_rad = AngleOf(motion);
      if (step_m > options.max_frame_translation_m ||
          step_rad > options.max_frame_rotation_deg * kDegToRad) {
        std::ostringstream why;
        why.precision(3);
        why << "implausible motion of " << step_m << " m, " << step_rad / kDegToRad
            << " deg since the previous frame (max " << options.max_frame_translation_m << " m, "
            << options.max_frame_rotation_deg << " deg)";
        lose(why.str());
        return r;
      }
      r.overlap_fraction = Overlap(p, keyframe_from_current);
      if (r.overlap_fraction < options.min_overlap_fraction) {
        lose("only " + Percent(r.overlap_fraction) +
             " of the points agree with the keyframe (min " +
             Percent(options.min_overlap_fraction) + ")");
        return r;
      }
      // Accepted.
      ++stats.tracked;
      last_motion = motion;
      last_dt_s = dt_s;
      world_from_last = world_from_current;
      distance_m += step_m;
      rotation_rad += step_rad;
      r.status = TrackingStatus::kTracking;
      const Eigen::Isometry3d rig_from_optical = RigFromOptical();
      r.previous_from_rig = rig_from_optical * motion * rig_from_optical.inverse();
      if (keyframe_from_current.translation().norm() > options.keyframe_translation_m ||
          AngleOf(keyframe_from_current) > options.keyframe_rotation_deg * kDegToRad) {
        SetKeyframe(p, current, world_from_current);
        r.keyframe = true;
      }
      Fill(&r);
      return r;
    } catch (const std::exception& e) {  // cv::Exception included: never crash the caller
      lose(std::string("OpenCV error: ") + e.what());
      return r;
    }
  }
};

RgbdOdometry::RgbdOdometry(const RgbdOdometryOptions& options) : impl_(std::make_unique<Impl>()) {
  common::ValidateOptions(options);
  impl_->options = options;
}

RgbdOdometry::~RgbdOdometry() = default;

RgbdOdometryResult RgbdOdometry::Process(const RgbdFrame& frame) {
  const auto t0 = std::chrono::steady_clock::now();
  RgbdOdometryResult r = impl_->Process(frame);
  r.compute_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

void RgbdOdometry::Reset() {
  const RgbdOdometryOptions options = impl_->options;
  impl_ = std::make_unique<Impl>();
  impl_->options = options;
}

bool RgbdOdometry::needs_image() const { return impl_->NeedsImage(); }
const RgbdOdometryOptions& RgbdOdometry::options() const { return impl_->options; }
const RgbdOdometryStats& RgbdOdometry::stats() const { return impl_->stats; }

}  // namespace rgbd_odometry
}  // namespace sarmap
