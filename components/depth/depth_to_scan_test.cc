// Depth-to-scan: synthetic scenes pin the geometry; a real Kinect frame pins the behaviour.

#include "depth/depth_to_scan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "common/robot_config.h"

namespace sarmap {
namespace depth {
namespace {

// The default robot: camera 0.55 m up at x = 0.10, looking forward, level (optical frame z
// forward, x right, y down).
Eigen::Isometry3d DefaultBaseFromCamera() {
  const common::RobotOptions robot;
  const common::Rigid3d bc = robot.base_from_camera.ToRigid3d();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = bc.rotation().toRotationMatrix();
  t.translation() = bc.translation();
  return t;
}

PinholeIntrinsics Kinect() { return {640, 480, 525, 525, 319.5, 239.5}; }

// Renders the depth (mm) of a scene for the default camera: a floor (z = 0), a wall at x = X
// (base frame) and optionally a table top (horizontal plane at height H for x in [a, b]).
std::vector<uint16_t> Render(double wall_x, double table_h = -1, double table_a = 0,
                             double table_b = 0) {
  const PinholeIntrinsics in = Kinect();
  const Eigen::Isometry3d bc = DefaultBaseFromCamera();
  std::vector<uint16_t> depth(in.width * in.height, 0);
  for (int v = 0; v < in.height; ++v) {
    for (int u = 0; u < in.width; ++u) {
      const Eigen::Vector3d ray =
          bc.linear() * Eigen::Vector3d((u - in.cx) / in.fx, (v - in.cy) / in.fy, 1);
      const Eigen::Vector3d o = bc.translation();
      double t = 1e9;  // depth along the optical axis = the ray parameter (z_cam = 1)
      if (ray.x() > 1e-9) t = std::min(t, (wall_x - o.x()) / ray.x());
      if (ray.z() < -1e-9) t = std::min(t, -o.z() / ray.z());
      if (table_h > 0 && std::abs(ray.z()) > 1e-9) {
        const double tt = (table_h - o.z()) / ray.z();
        const Eigen::Vector3d p = o + tt * ray;
        if (tt > 0 && p.x() >= table_a && p.x() <= table_b) t = std::min(t, tt);
      }
      if (t < 20) depth[v * in.width + u] = static_cast<uint16_t>(std::lround(t * 1000));
    }
  }
  return depth;
}

TEST(DepthToScanTest, WallInFrontGivesItsDistancePerAzimuth) {
  DepthToScanOptions o;
  DepthToScan conv(o, Kinect(), DefaultBaseFromCamera());
  const auto depth = Render(2.5);
  const PlanarScan s = conv.Convert(depth.data(), 0.001);
  ASSERT_EQ(static_cast<int>(s.ranges_m.size()), 640);
  int checked = 0;
  for (size_t b = 0; b < s.ranges_m.size(); ++b) {
    const float r = s.ranges_m[b];
    if (!(r > 0) || !std::isfinite(r)) continue;
    const double az = s.angle_min_rad + b * s.angle_increment_rad;
    EXPECT_NEAR(r, 2.5 / std::cos(az), 0.02) << "bin " << b;  // wall x = 2.5 in base
    ++checked;
  }
  EXPECT_GT(checked, 560);
  // The field of view is about +-31 deg for fx = 525 (a little less seen from the base
  // origin, 0.1 m behind the camera, at 2 m), plus a 0.02 rad margin.
  const double edge = -std::atan2(2.0 * 319.5 / 525, 2.1);
  EXPECT_NEAR(s.angle_min_rad, edge - 0.02, 1e-3);
}

TEST(DepthToScanTest, ALowObjectIsVisibleOnlyFromWhereItsTopIsInTheView) {
  DepthToScanOptions o;
  DepthToScan conv(o, Kinect(), DefaultBaseFromCamera());
  // Rubble: a slab 0.19 m high from x = 1.5 to 2.0 m, a wall at 4 m behind it.
  const PlanarScan low = conv.Convert(Render(4.0, 0.19, 1.5, 2.0).data(), 0.001);
  // The view's lowest ray, at the bottom row's corner (the shallowest of the row): tan =
  // (239.5 / 525) / hypot(1, 319.5 / 525). The slab's top, 0.36 m below the lens, leaves the
  // view nearer than 0.36 / tan.
  const double tan_down = (239.5 / 525) / std::hypot(1.0, 319.5 / 525);
  const double expected = (0.55 - 0.19) / tan_down;
  ASSERT_EQ(low.visible_from_m.size(), low.ranges_m.size());
  int checked = 0;
  for (size_t b = 0; b < low.ranges_m.size(); ++b) {
    if (!(low.ranges_m[b] > 0 && low.ranges_m[b] < 2.1)) continue;
    EXPECT_NEAR(low.visible_from_m[b], expected, 0.01) << "bin " << b;
    ++checked;
  }
  EXPECT_GT(checked, 300);
  // A wall spans the lens height: seen down to the sensor's minimum range. No return: 0.
  const PlanarScan wall = conv.Convert(Render(2.5).data(), 0.001);
  for (size_t b = 0; b < wall.ranges_m.size(); ++b) {
    if (wall.ranges_m[b] > 0 && std::isfinite(wall.ranges_m[b])) {
      EXPECT_FLOAT_EQ(wall.visible_from_m[b], static_cast<float>(o.range_min_m)) << "bin " << b;
    } else {
      EXPECT_EQ(wall.visible_from_m[b], 0.0f) << "bin " << b;
    }
  }
}

TEST(DepthToScanTest, TableTopInsideTheBandIsAnObstacle) {
  DepthToScanOptions o;
  o.max_height_m = 1.0;
  DepthToScan conv(o, Kinect(), DefaultBaseFromCamera());
  // A table top at 0.7 m height from x = 1.2 to 2.0 in front of a wall at 3 m: a single scan
  // row at camera height (0.55 m) would see the wall; the band sees the table's front edge
  // (its underside is not rendered, so the nearest in-band point is where the camera sees the
  // top surface begin... the top is above the camera, seen from below as the plane z = 0.7).
  const auto depth = Render(3.0, 0.7, 1.2, 2.0);
  const PlanarScan s = conv.Convert(depth.data(), 0.001);
  const size_t centre = 320;
  EXPECT_LT(s.ranges_m[centre], 2.05f);
  EXPECT_GT(s.ranges_m[centre], 1.15f);
  // Lower the band's top below the table: the wall appears instead.
  o.max_height_m = 0.6;
  DepthToScan low(o, Kinect(), DefaultBaseFromCamera());
  EXPECT_NEAR(low.Convert(depth.data(), 0.001).ranges_m[centre], 3.0f, 0.03f);
}

// A Kinect's depth noise (Khoshelham & Elberink 2012): Gaussian in disparity, sigma_z = k z^2,
// k = 1.425e-3, disparity quantised to 1/8 pixel, as the simulator renders it.
std::vector<uint16_t> AddKinectNoise(const std::vector<uint16_t>& depth_mm, uint32_t seed) {
  constexpr double kBf = 0.075 * 525, kK = 1.425e-3, kSubpixel = 8;
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, kK * kBf);
  std::vector<uint16_t> out(depth_mm.size(), 0);
  for (size_t i = 0; i < depth_mm.size(); ++i) {
    if (depth_mm[i] == 0) continue;
    double disparity = kBf / (depth_mm[i] * 1e-3) + normal(rng);
    disparity = std::floor(disparity * kSubpixel + 0.5) / kSubpixel;
    if (disparity > 0) out[i] = static_cast<uint16_t>(std::lround(kBf * 1000 / disparity));
  }
  return out;
}

// The mean signed error of the scan's ranges against a wall at x = wall_x (base frame).
double MeanRangeError(const PlanarScan& s, double wall_x) {
  double sum = 0;
  int n = 0;
  for (size_t b = 0; b < s.ranges_m.size(); ++b) {
    const float r = s.ranges_m[b];
    if (!(r > 0) || !std::isfinite(r)) continue;
    sum += r - wall_x / std::cos(s.angle_min_rad + b * s.angle_increment_rad);
    ++n;
  }
  return n > 0 ? sum / n : 1e9;
}

// Each beam is the minimum of ~70 noisy pixels of the wall: biased short by ~2.4 sigma, a
// bias that grows with range (a scan that shrinks with range makes SLAM fall behind in every
// metre driven into new space). The median of the nearest surface's pixels is not biased.
TEST(DepthToScanTest, NoisyWallIsNotPulledCloserByTheMinimum) {
  DepthToScanOptions o;
  o.row_step = 2;  // config/depth.yaml
  DepthToScan minimum(o, Kinect(), DefaultBaseFromCamera());
  o.range_noise_k = 1.425e-3;
  DepthToScan surface(o, Kinect(), DefaultBaseFromCamera());
  for (double wall_x : {2.0, 3.0, 4.0, 4.3, 4.4, 4.45}) {
    const auto depth = AddKinectNoise(Render(wall_x), static_cast<uint32_t>(wall_x * 10));
    const double sigma = 1.425e-3 * wall_x * wall_x;
    const double min_error = MeanRangeError(minimum.Convert(depth.data(), 0.001), wall_x);
    const double surface_error = MeanRangeError(surface.Convert(depth.data(), 0.001), wall_x);
    // A bin with nothing in it stays "no information" (0), never "no return" (+inf): a wall
    // well inside the range limit gives no +inf beam.
    if (wall_x <= 3.0) {
      for (float r : surface.Convert(depth.data(), 0.001).ranges_m) EXPECT_FALSE(std::isinf(r));
    }
    EXPECT_LT(min_error, -1.5 * sigma) << "wall at " << wall_x << " m";
    EXPECT_LT(std::abs(surface_error), 0.25 * sigma + 0.002) << "wall at " << wall_x << " m";
  }
  // A table edge nearer than the wall in the same beams is still what the beam reports.
  const auto table = AddKinectNoise(Render(3.0, 0.7, 1.2, 2.0), 7);
  const PlanarScan s = surface.Convert(table.data(), 0.001);
  EXPECT_LT(s.ranges_m[320], 2.05f);
  EXPECT_GT(s.ranges_m[320], 1.15f);
}

TEST(DepthToScanTest, FloorOnlyAndInvalidPixels) {
  DepthToScanOptions o;
  DepthToScan conv(o, Kinect(), DefaultBaseFromCamera());
  // Nothing valid: every bin is "no information" (0, below range_min).
  std::vector<uint16_t> none(640 * 480, 0);
  for (float r : conv.Convert(none.data(), 0.001).ranges_m) EXPECT_EQ(r, 0.0f);
  // Wall beyond range_max: no return (+inf) where it is seen.
  const auto far = Render(8.0);
  int inf = 0;
  for (float r : conv.Convert(far.data(), 0.001).ranges_m) inf += std::isinf(r);
  EXPECT_GT(inf, 600);
}

TEST(DepthToScanTest, RealKinectFrame) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/depth/kinect_slambook2_ch5/depth/1.pgm";
  if (!std::ifstream(path)) GTEST_SKIP() << "shared data missing: " << path;
  const cv::Mat d = cv::imread(path, cv::IMREAD_ANYDEPTH);
  ASSERT_EQ(d.type(), CV_16UC1);
  ASSERT_EQ(d.cols, 640);
  // slambook2 ch5 intrinsics, depth in mm.
  const PinholeIntrinsics in{d.cols, d.rows, 518.0, 519.0, 325.5, 253.5};
  DepthToScanOptions o;
  DepthToScan conv(o, in, DefaultBaseFromCamera());
  std::vector<uint16_t> depth(d.begin<uint16_t>(), d.end<uint16_t>());
  const PlanarScan s = conv.Convert(depth.data(), 0.001);
  int returns = 0, zeros = 0;
  for (size_t b = 0; b < s.ranges_m.size(); ++b) {
    const float r = s.ranges_m[b];
    EXPECT_FALSE(std::isnan(r));
    if (std::isfinite(r) && r > 0) {
      ++returns;
      EXPECT_GE(r, 0.3f);
      EXPECT_LE(r, 4.5f);
    }
    zeros += r == 0.0f;
  }
  // An indoor scene: most bins see an obstacle in the band.
  EXPECT_GT(returns, 400);
  EXPECT_GT(s.in_band_pixels, 10000);
  EXPECT_GT(s.invalid_pixels, 0);  // Kinect frames have holes
  // Each return equals a brute-force minimum over the pixels of its bin.
  const Eigen::Isometry3d bc = DefaultBaseFromCamera();
  std::vector<float> brute(s.ranges_m.size(), 1e9f);
  for (int v = 0; v < d.rows; ++v) {
    for (int u = 0; u < d.cols; ++u) {
      const double z = d.at<uint16_t>(v, u) * 0.001;
      if (z < o.range_min_m || z > o.range_max_m) continue;
      const Eigen::Vector3d p =
          bc * Eigen::Vector3d((u - in.cx) / in.fx * z, (v - in.cy) / in.fy * z, z);
      if (p.z() < o.min_height_m || p.z() > o.max_height_m) continue;
      if (std::hypot(p.x(), p.y()) > o.range_max_m) continue;
      const long bin =
          std::lround((std::atan2(p.y(), p.x()) - s.angle_min_rad) / s.angle_increment_rad);
      if (bin < 0 || bin >= static_cast<long>(brute.size())) continue;
      brute[bin] = std::min(brute[bin], static_cast<float>(std::hypot(p.x(), p.y())));
    }
  }
  for (size_t b = 0; b < s.ranges_m.size(); ++b) {
    if (brute[b] < 1e8f) {
      EXPECT_NEAR(s.ranges_m[b], brute[b], 1e-3) << "bin " << b;
    }
  }
}

}  // namespace
}  // namespace depth
}  // namespace sarmap
