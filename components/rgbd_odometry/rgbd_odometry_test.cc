// RgbdOdometry: a synthetic textured room rendered from known poses pins the geometry and the
// conventions; real TUM fr1/xyz pairs and the slambook2 Kinect frames pin the accuracy.

#include "rgbd_odometry/rgbd_odometry.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <ostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "rgbd_odometry/synthetic_room.h"

namespace sarmap {
namespace rgbd_odometry {
namespace {

constexpr double kDeg = M_PI / 180.0;
using synthetic::Moved;
using synthetic::Room;
using synthetic::StartPose;

struct Error {
  double translation_m, rotation_deg;
};
Error Compare(const Eigen::Isometry3d& truth, const Eigen::Isometry3d& estimate) {
  const Eigen::Isometry3d e = truth.inverse() * estimate;
  return {e.translation().norm(), Eigen::AngleAxisd(e.linear()).angle() / kDeg};
}

RgbdOdometryOptions Options(const std::string& method, double scale) {
  RgbdOdometryOptions o;
  o.method = method;
  o.image_scale = scale;
  return o;
}

// ---------------------------------------------------------------------------------------------

struct MethodCase {
  std::string method;
  double scale;
};
// Test parameters print as their method and scale (not as raw bytes in the test listing).
void PrintTo(const MethodCase& c, std::ostream* os) { *os << c.method << " x" << c.scale; }
std::string CaseName(const testing::TestParamInfo<MethodCase>& info) {
  return info.param.method + (info.param.scale == 1.0 ? "_full" : "_half");
}
const std::vector<MethodCase> kAllCases = {{"rgbd", 1.0},     {"rgbd", 0.5},     {"icp", 1.0},
                                           {"icp", 0.5},      {"rgbd_icp", 1.0}, {"rgbd_icp", 0.5},
                                           {"fast_icp", 1.0}, {"fast_icp", 0.5}};

class SyntheticMotion : public testing::TestWithParam<MethodCase> {};

TEST_P(SyntheticMotion, RecoversAKnownMotion) {
  const Room room;
  const Eigen::Isometry3d a = StartPose();
  const Eigen::Isometry3d b = Moved(a, {0.03, -0.02, 0.015}, {0.3, 0.2, 1.0}, 2.0 * kDeg);
  RgbdOdometry odo(Options(GetParam().method, GetParam().scale));
  const RgbdOdometryResult ra = odo.Process(room.Render(a, 1000000));
  ASSERT_EQ(ra.status, TrackingStatus::kInitialised) << ra.message;
  EXPECT_TRUE(ra.keyframe);
  EXPECT_TRUE(ra.world_from_optical.isApprox(Eigen::Isometry3d::Identity()));
  const RgbdOdometryResult rb = odo.Process(room.Render(b, 1033333));
  ASSERT_EQ(rb.status, TrackingStatus::kTracking) << rb.message;
  const Error e = Compare(a.inverse() * b, rb.world_from_optical);
  std::printf("[ synthetic ] %-8s scale %.1f: %.3f mm %.4f deg, overlap %.2f, %.1f ms\n",
              GetParam().method.c_str(), GetParam().scale, e.translation_m * 1e3, e.rotation_deg,
              rb.overlap_fraction, rb.compute_ms);
  // 1 mm and 0.1 deg; the photometric method alone at half resolution gets 1.55 mm.
  const bool coarse = GetParam().method == "rgbd" && GetParam().scale < 1;
  EXPECT_LT(e.translation_m, coarse ? 2e-3 : 1e-3);
  EXPECT_LT(e.rotation_deg, 0.1);
  EXPECT_GT(rb.overlap_fraction, 0.9);
}

// In the dark (a black image) the photometric term has nothing to work with: rgbd_icp goes on
// with the depth alone, rgbd alone fails (reported lost, not a wrong pose).
TEST(RgbdOdometryDarkness, RgbdIcpFallsBackToDepthAndRgbdIsLost) {
  const Room room;
  const Eigen::Isometry3d a = StartPose();
  const Eigen::Isometry3d b = Moved(a, {0.03, -0.02, 0.015}, {0.3, 0.2, 1.0}, 2.0 * kDeg);
  RgbdFrame fa = room.Render(a, 1000000), fb = room.Render(b, 1033333);
  std::fill(fa.image.begin(), fa.image.end(), 0);
  std::fill(fb.image.begin(), fb.image.end(), 0);
  RgbdOdometry both(Options("rgbd_icp", 0.5));
  ASSERT_TRUE(both.Process(fa).ok());
  const RgbdOdometryResult r = both.Process(fb);
  ASSERT_EQ(r.status, TrackingStatus::kTracking) << r.message;
  const Error e = Compare(a.inverse() * b, r.world_from_optical);
  EXPECT_LT(e.translation_m, 1e-3);
  EXPECT_LT(e.rotation_deg, 0.1);
  RgbdOdometry photometric(Options("rgbd", 0.5));
  ASSERT_TRUE(photometric.Process(fa).ok());
  const RgbdOdometryResult lost = photometric.Process(fb);
  EXPECT_EQ(lost.status, TrackingStatus::kLost);
  std::printf("[ dark      ] rgbd_icp %.3f mm %.4f deg; rgbd: %s (%s)\n", e.translation_m * 1e3,
              e.rotation_deg, TrackingStatusName(lost.status), lost.message.c_str());
}

INSTANTIATE_TEST_SUITE_P(Methods, SyntheticMotion, testing::ValuesIn(kAllCases), CaseName);

TEST(RgbdOdometryConvention, RigFromOpticalAxes) {
  const Eigen::Isometry3d t = RigFromOptical();
  EXPECT_TRUE(t.linear().isApprox(t.linear().transpose().inverse()));  // a rotation
  EXPECT_NEAR(t.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE((t.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((t.linear() * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((t.linear() * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(t.translation().isZero());
}

// Walking forward (along the view) and turning left is +x and +yaw in the rig (body) frame;
// stepping right is -y; rising is +z.
TEST(RgbdOdometryConvention, ForwardLeftAndUpInTheBodyFrame) {
  const Room room;
  const Eigen::Isometry3d a = StartPose();
  // In the world (= rig at the start: x forward, y left, z up): 4 cm forward, 2 cm to the
  // right, 1 cm up, and a 3 deg turn to the left (about +z).
  const Eigen::Isometry3d b = Moved(a, {0.04, -0.02, 0.01}, Eigen::Vector3d::UnitZ(), 3.0 * kDeg);
  RgbdOdometry odo(Options("icp", 0.5));
  ASSERT_TRUE(odo.Process(room.Render(a, 0 + 1)).ok());
  const RgbdOdometryResult r = odo.Process(room.Render(b, 33334));
  ASSERT_EQ(r.status, TrackingStatus::kTracking) << r.message;
  const Eigen::Vector3d p = r.world_from_rig.translation();
  EXPECT_NEAR(p.x(), 0.04, 2e-3);
  EXPECT_NEAR(p.y(), -0.02, 2e-3);
  EXPECT_NEAR(p.z(), 0.01, 2e-3);
  const Eigen::Vector3d ypr = r.world_from_rig.linear().eulerAngles(2, 1, 0);
  EXPECT_NEAR(ypr[0], 3.0 * kDeg, 0.2 * kDeg);
  // The rig's forward axis turned towards +y (left).
  const Eigen::Vector3d forward = r.world_from_rig.linear() * Eigen::Vector3d::UnitX();
  EXPECT_GT(forward.y(), 0.04);
  EXPECT_TRUE(r.previous_from_rig.isApprox(r.world_from_rig, 1e-9));
  // The optical pose says the same in the optical convention.
  EXPECT_TRUE(RigPoseFromOpticalPose(r.world_from_optical).isApprox(r.world_from_rig, 1e-12));
  EXPECT_NEAR(r.world_from_optical.translation().z(), 0.04, 2e-3);   // optical z = forward
  EXPECT_NEAR(r.world_from_optical.translation().x(), 0.02, 2e-3);   // optical x = right
  EXPECT_NEAR(r.world_from_optical.translation().y(), -0.01, 2e-3);  // optical y = down
}

// A smooth hand-held path of 30 frames (1.5 cm and 0.5 deg per frame): the pose follows the
// truth, keyframes come every ~10 cm, and nothing is lost.
class SyntheticPath : public testing::TestWithParam<MethodCase> {};

TEST_P(SyntheticPath, FollowsAPathWithKeyframes) {
  const Room room;
  RgbdOdometry odo(Options(GetParam().method, GetParam().scale));
  const Eigen::Isometry3d start = StartPose();
  Eigen::Isometry3d truth = start;
  int keyframes = 0;
  Error worst{0, 0};
  for (int i = 0; i < 30; ++i) {
    if (i > 0) {
      truth = Moved(truth, {0.012, 0.006, 0.006 * std::sin(i * 0.3)}, {0.2, 0.1, 1.0}, 0.5 * kDeg);
    }
    const RgbdOdometryResult r = odo.Process(room.Render(truth, 1000000 + i * 33333));
    ASSERT_TRUE(r.ok()) << "frame " << i << ": " << r.message;
    keyframes += r.keyframe;
    const Error e = Compare(start.inverse() * truth, r.world_from_optical);
    worst.translation_m = std::max(worst.translation_m, e.translation_m);
    worst.rotation_deg = std::max(worst.rotation_deg, e.rotation_deg);
  }
  const RgbdOdometryResult last = odo.Process(room.Render(truth, 1000000 + 30 * 33333));
  std::printf(
      "[ path      ] %-8s scale %.1f: 30 frames, %.2f m: worst %.2f mm %.3f deg, %d keyframes\n",
      GetParam().method.c_str(), GetParam().scale, last.distance_m, worst.translation_m * 1e3,
      worst.rotation_deg, keyframes);
  EXPECT_EQ(odo.stats().tracked, 30);
  EXPECT_EQ(odo.stats().lost, 0);
  // 29 steps of ~1.4 cm = 0.41 m: a keyframe at the start and about every 10 cm after.
  EXPECT_NEAR(last.distance_m, 0.41, 0.03);
  EXPECT_GE(keyframes, 4);
  EXPECT_LE(keyframes, 6);
  // Measured: the photometric method alone drifts 5.0 mm and 0.10 deg over the path, the others
  // 0.7-0.8 mm and 0.01 deg.
  const bool photometric = GetParam().method == "rgbd";
  EXPECT_LT(worst.translation_m, photometric ? 8e-3 : 2e-3);
  EXPECT_LT(worst.rotation_deg, photometric ? 0.2 : 0.05);
}

INSTANTIATE_TEST_SUITE_P(Methods, SyntheticPath,
                         testing::Values(MethodCase{"rgbd", 0.5}, MethodCase{"icp", 0.5},
                                         MethodCase{"rgbd_icp", 0.5}, MethodCase{"fast_icp", 0.5}),
                         CaseName);

// ---------------------------------------------------------------------------------------------
// Failures are statuses, never crashes.

TEST(RgbdOdometryFailures, MalformedInputIsInvalidAndChangesNothing) {
  const Room room;
  RgbdOdometry odo(Options("rgbd", 0.5));
  const RgbdFrame good = room.Render(StartPose(), 1000000);
  ASSERT_EQ(odo.Process(good).status, TrackingStatus::kInitialised);

  auto expect_invalid = [&](RgbdFrame f, const std::string& words) {
    const RgbdOdometryResult r = odo.Process(f);
    EXPECT_EQ(r.status, TrackingStatus::kInvalidInput) << words;
    EXPECT_NE(r.message.find(words), std::string::npos)
        << "'" << r.message << "' lacks '" << words << "'";
    EXPECT_TRUE(r.world_from_rig.isApprox(Eigen::Isometry3d::Identity()));
  };
  RgbdFrame f = good;
  f.utime += 1000;
  RgbdFrame empty;
  empty.utime = f.utime;
  expect_invalid(empty, "empty");
  RgbdFrame short_depth = f;
  short_depth.depth.resize(100);
  expect_invalid(short_depth, "depth has 100 values");
  RgbdFrame wrong_image = f;
  wrong_image.image.resize(320 * 240);
  expect_invalid(wrong_image, "image has 76800 bytes");
  RgbdFrame channels = f;
  channels.image_channels = 2;
  expect_invalid(channels, "channels");
  RgbdFrame no_image = f;
  no_image.image.clear();
  expect_invalid(no_image, "needs an image");
  RgbdFrame bad_camera = f;
  bad_camera.camera.fx = std::nan("");
  expect_invalid(bad_camera, "intrinsics");
  RgbdFrame zero_camera = f;
  zero_camera.camera.fy = 0;
  expect_invalid(zero_camera, "intrinsics");
  RgbdFrame bad_unit = f;
  bad_unit.depth_unit_m = 0;
  expect_invalid(bad_unit, "depth unit");
  RgbdFrame old = f;
  old.utime = good.utime;
  expect_invalid(old, "not after");
  EXPECT_EQ(odo.stats().invalid, 9);
  // Tracking goes on as if nothing happened.
  const RgbdOdometryResult r = odo.Process(f);
  EXPECT_EQ(r.status, TrackingStatus::kTracking) << r.message;
  EXPECT_LT(r.world_from_rig.translation().norm(), 1e-3);
  EXPECT_EQ(odo.stats().lost, 0);
}

TEST(RgbdOdometryFailures, NoDepthIsLostThenReinitialisedAtTheHeldPose) {
  const Room room;
  RgbdOdometry odo(Options("icp", 0.5));
  const Eigen::Isometry3d a = StartPose();
  const Eigen::Isometry3d b = Moved(a, {0.03, 0, 0}, Eigen::Vector3d::UnitZ(), 0);
  const Eigen::Isometry3d c = Moved(b, {0.05, 0, 0}, Eigen::Vector3d::UnitZ(), 0);
  const Eigen::Isometry3d d = Moved(c, {0.02, 0.01, 0}, Eigen::Vector3d::UnitZ(), 1.0 * kDeg);
  ASSERT_TRUE(odo.Process(room.Render(a, 100000)).ok());
  const RgbdOdometryResult rb = odo.Process(room.Render(b, 133333));
  ASSERT_EQ(rb.status, TrackingStatus::kTracking) << rb.message;
  EXPECT_NEAR(rb.world_from_rig.translation().x(), 0.03, 1e-3);

  RgbdFrame blind = room.Render(c, 166666);
  std::fill(blind.depth.begin(), blind.depth.end(), 0);
  const RgbdOdometryResult lost = odo.Process(blind);
  EXPECT_EQ(lost.status, TrackingStatus::kLost);
  EXPECT_NE(lost.message.find("valid"), std::string::npos) << lost.message;
  EXPECT_TRUE(lost.world_from_rig.isApprox(rb.world_from_rig));  // held
  // Out-of-range depth (all beyond max_depth_m) is no depth either.
  RgbdFrame far = room.Render(c, 199999);
  std::fill(far.depth.begin(), far.depth.end(), 9000);
  EXPECT_EQ(odo.Process(far).status, TrackingStatus::kLost);

  // The next good frame (c, 5 cm farther than b) is a new keyframe at the held pose: the motion
  // during the loss is not recovered.
  const RgbdOdometryResult rc = odo.Process(room.Render(c, 233333));
  EXPECT_EQ(rc.status, TrackingStatus::kReinitialised) << rc.message;
  EXPECT_TRUE(rc.keyframe);
  EXPECT_TRUE(rc.world_from_rig.isApprox(rb.world_from_rig));
  EXPECT_EQ(rc.relocalisations, 1);
  // Tracking resumes from there.
  const RgbdOdometryResult rd = odo.Process(room.Render(d, 266666));
  ASSERT_EQ(rd.status, TrackingStatus::kTracking) << rd.message;
  const Error e = Compare(b.inverse() * d, c.inverse() * d);  // not a test, a reminder of frames
  (void)e;
  const Eigen::Isometry3d expected = rb.world_from_optical * (c.inverse() * d);
  const Error err = Compare(expected, rd.world_from_optical);
  EXPECT_LT(err.translation_m, 1e-3);
  EXPECT_LT(err.rotation_deg, 0.1);
  EXPECT_EQ(odo.stats().lost, 2);
  EXPECT_EQ(odo.stats().relocalisations, 1);
  // The covariance grew by the relocalisation term.
  const PoseCovarianceOptions co;
  EXPECT_GT(PoseCovariance(co, rd)(0, 0), std::pow(co.relocalisation_sigma_m, 2));
}

TEST(RgbdOdometryFailures, FirstFrameWithoutDepthCreatesNoWorld) {
  const Room room;
  RgbdOdometry odo(Options("icp", 0.5));
  RgbdFrame blind = room.Render(StartPose(), 1);
  std::fill(blind.depth.begin(), blind.depth.end(), 0);
  EXPECT_EQ(odo.Process(blind).status, TrackingStatus::kLost);
  EXPECT_EQ(odo.Process(room.Render(StartPose(), 2)).status, TrackingStatus::kInitialised);
  EXPECT_EQ(odo.stats().relocalisations, 0);
}

// A jump to an unrelated view (1.5 m away, turned 120 deg) is not tracked: lost, pose held.
TEST(RgbdOdometryFailures, ImplausibleJumpIsLost) {
  const Room room;
  for (const std::string method : {"rgbd", "icp", "rgbd_icp", "fast_icp"}) {
    RgbdOdometry odo(Options(method, 0.5));
    const Eigen::Isometry3d a = StartPose();
    const Eigen::Isometry3d far = Moved(a, {-1.5, 0.5, 0}, Eigen::Vector3d::UnitZ(), 120 * kDeg);
    ASSERT_TRUE(odo.Process(room.Render(a, 1)).ok());
    const RgbdOdometryResult r = odo.Process(room.Render(far, 2));
    EXPECT_EQ(r.status, TrackingStatus::kLost) << method;
    EXPECT_FALSE(r.message.empty());
    EXPECT_TRUE(r.world_from_rig.isApprox(Eigen::Isometry3d::Identity())) << method;
    std::printf("[ jump      ] %-8s: %s\n", method.c_str(), r.message.c_str());
  }
}

// Frames too small for the pyramid (OpenCV asserts inside) are a status, not a crash.
TEST(RgbdOdometryFailures, TinyFramesAreAStatusNotACrash) {
  for (const std::string method : {"rgbd", "icp", "rgbd_icp", "fast_icp"}) {
    for (const double scale : {1.0, 0.5}) {
      RgbdOdometry odo(Options(method, scale));
      int64_t t = 1;
      for (const auto& [w, h] :
           std::vector<std::pair<int, int>>{{1, 1}, {7, 5}, {33, 17}, {2, 900}}) {
        for (int repeat = 0; repeat < 2; ++repeat) {
          RgbdFrame f;
          f.utime = t++;
          f.width = w;
          f.height = h;
          f.depth.assign(static_cast<size_t>(w) * h, 1500);
          f.image.assign(static_cast<size_t>(w) * h, 100);
          f.image_channels = 1;
          f.camera = {w * 0.8, w * 0.8, w / 2.0, h / 2.0};
          const RgbdOdometryResult r = odo.Process(f);
          EXPECT_NE(r.status, TrackingStatus::kInvalidInput) << method << " " << w << "x" << h;
          if (!r.ok()) {
            EXPECT_FALSE(r.message.empty());
          }
        }
      }
    }
  }
}

TEST(RgbdOdometryFailures, InvalidOptionsThrowAtConstruction) {
  RgbdOdometryOptions o;
  o.method = "orb";
  EXPECT_THROW(RgbdOdometry{o}, common::OptionsError);
  o = RgbdOdometryOptions();
  o.max_depth_m = 0.1;
  EXPECT_THROW(RgbdOdometry{o}, common::OptionsError);
  o = RgbdOdometryOptions();
  o.iteration_counts = {};
  EXPECT_THROW(RgbdOdometry{o}, common::OptionsError);
}

TEST(RgbdOdometryCovariance, GrowsWithThePath) {
  const PoseCovarianceOptions o;
  RgbdOdometryResult r;
  const auto c0 = PoseCovariance(o, r);
  EXPECT_NEAR(c0(0, 0), o.position_sigma_m * o.position_sigma_m, 1e-15);
  r.distance_m = 10;
  r.rotation_rad = 2;
  const auto c1 = PoseCovariance(o, r);
  EXPECT_NEAR(std::sqrt(c1(1, 1)), o.position_sigma_m + 10 * o.position_drift, 1e-12);
  EXPECT_GT(c1(5, 5), c0(5, 5));
  EXPECT_EQ(c1(0, 1), 0.0);
  EXPECT_TRUE(c1.isApprox(c1.transpose()));
}

// ---------------------------------------------------------------------------------------------
// Real frames (shared/data/depth; skipped when absent).

std::string DataDir() { return std::string(SARMAP_DATA_DIR) + "/depth"; }

bool ReadPose(const std::string& path, Eigen::Isometry3d* pose, int line_no = 0) {
  std::ifstream in(path);
  std::string line;
  for (int i = 0; i <= line_no; ++i) {
    if (!std::getline(in, line)) return false;
  }
  std::istringstream s(line);
  double tx, ty, tz, qx, qy, qz, qw;
  if (!(s >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) return false;
  pose->setIdentity();
  pose->linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  pose->translation() = Eigen::Vector3d(tx, ty, tz);
  return true;
}

// A colour PNG + 16-bit depth image as an RgbdFrame (RGB order).
bool LoadFrame(const std::string& color_path, const std::string& depth_path, double unit,
               const PinholeCamera& cam, int64_t utime, RgbdFrame* f) {
  const cv::Mat bgr = cv::imread(color_path, cv::IMREAD_COLOR);
  const cv::Mat depth = cv::imread(depth_path, cv::IMREAD_ANYDEPTH);
  if (bgr.empty() || depth.empty() || depth.type() != CV_16UC1 || bgr.size() != depth.size()) {
    return false;
  }
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  f->utime = utime;
  f->width = depth.cols;
  f->height = depth.rows;
  f->depth.assign(depth.begin<uint16_t>(), depth.end<uint16_t>());
  f->depth_unit_m = unit;
  f->image.assign(rgb.data, rgb.data + rgb.total() * 3);
  f->image_channels = 3;
  f->camera = cam;
  return true;
}

struct Bound {
  double translation_m, rotation_deg;
};

// Bounds: the measured errors (README) with about 50 % margin.
struct RealCase {
  std::string method;
  double scale;
  Bound case_1, case_2;
};
void PrintTo(const RealCase& c, std::ostream* os) { *os << c.method << " x" << c.scale; }

class TumPairs : public testing::TestWithParam<RealCase> {};

TEST_P(TumPairs, RelativeMotionMatchesTheTruth) {
  const RealCase& rc = GetParam();
  for (int c = 1; c <= 2; ++c) {
    const std::string dir = DataDir() + "/tum_fr1xyz_pairs/case_" + std::to_string(c);
    if (!std::ifstream(dir + "/pose_prev.txt")) GTEST_SKIP() << "shared data missing: " << dir;
    Eigen::Isometry3d world_from_prev, world_from_curr;
    ASSERT_TRUE(ReadPose(dir + "/pose_prev.txt", &world_from_prev));
    ASSERT_TRUE(ReadPose(dir + "/pose_curr.txt", &world_from_curr));
    const PinholeCamera cam{525.0, 525.0, 319.5, 239.5};  // kinect_params.txt
    RgbdFrame prev, curr;
    ASSERT_TRUE(
        LoadFrame(dir + "/img_prev.png", dir + "/dep_prev.png", 1.0 / 5000, cam, 1000000, &prev));
    ASSERT_TRUE(
        LoadFrame(dir + "/img_curr.png", dir + "/dep_curr.png", 1.0 / 5000, cam, 1033333, &curr));
    RgbdOdometry odo(Options(rc.method, rc.scale));
    ASSERT_EQ(odo.Process(prev).status, TrackingStatus::kInitialised);
    const RgbdOdometryResult r = odo.Process(curr);
    const Eigen::Isometry3d truth = world_from_prev.inverse() * world_from_curr;
    const Error e = Compare(truth, r.world_from_optical);
    std::printf(
        "[ tum case_%d ] %-8s scale %.1f: %s, truth %.1f mm %.2f deg, error %.2f mm %.3f deg, "
        "overlap %.2f\n",
        c, rc.method.c_str(), rc.scale, TrackingStatusName(r.status),
        truth.translation().norm() * 1e3, Eigen::AngleAxisd(truth.linear()).angle() / kDeg,
        e.translation_m * 1e3, e.rotation_deg, r.overlap_fraction);
    const Bound b = c == 1 ? rc.case_1 : rc.case_2;
    ASSERT_EQ(r.status, TrackingStatus::kTracking) << r.message;
    EXPECT_LT(e.translation_m, b.translation_m);
    EXPECT_LT(e.rotation_deg, b.rotation_deg);
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, TumPairs,
                         testing::Values(RealCase{"rgbd", 1.0, {0.010, 0.30}, {0.010, 0.20}},
                                         RealCase{"rgbd", 0.5, {0.010, 0.33}, {0.012, 0.36}},
                                         RealCase{"icp", 1.0, {0.007, 0.25}, {0.004, 1.00}},
                                         RealCase{"icp", 0.5, {0.007, 0.25}, {0.004, 1.10}},
                                         RealCase{"rgbd_icp", 1.0, {0.009, 0.25}, {0.008, 0.25}},
                                         RealCase{"rgbd_icp", 0.5, {0.008, 0.25}, {0.006, 0.50}},
                                         RealCase{"fast_icp", 1.0, {0.007, 0.30}, {0.007, 1.00}},
                                         RealCase{"fast_icp", 0.5, {0.007, 0.30}, {0.008, 1.00}}),
                         [](const testing::TestParamInfo<RealCase>& info) {
                           return info.param.method + (info.param.scale == 1.0 ? "_full" : "_half");
                         });

// slambook2 ch5: five Kinect frames 23 to 73 cm and 4 to 26 deg apart (world_from_camera
// poses). Dense odometry converges only within a few cm of the answer, so these steps are far
// outside its reach from a constant-velocity guess.
struct Slambook {
  std::vector<RgbdFrame> frames;
  std::vector<Eigen::Isometry3d> world_from_camera;
  bool Load() {
    const std::string dir = DataDir() + "/kinect_slambook2_ch5";
    const PinholeCamera cam{518.0, 519.0, 325.5, 253.5};  // as depth_to_scan_test.cc
    for (int i = 1; i <= 5; ++i) {
      Eigen::Isometry3d pose;
      RgbdFrame f;
      if (!ReadPose(dir + "/pose.txt", &pose, i - 1) ||
          !LoadFrame(dir + "/color/" + std::to_string(i) + ".png",
                     dir + "/depth/" + std::to_string(i) + ".pgm", 0.001, cam, i * 1000000, &f)) {
        return false;
      }
      frames.push_back(std::move(f));
      world_from_camera.push_back(pose);
    }
    return true;
  }
  Eigen::Isometry3d Truth(int i) const {  // optical prev_from_curr of step i -> i+1 (0-based)
    return world_from_camera[i].inverse() * world_from_camera[i + 1];
  }
};

RgbdOdometryOptions FarApartOptions(const MethodCase& c) {
  RgbdOdometryOptions o = Options(c.method, c.scale);
  o.max_frame_translation_m = 1.0;  // these steps are plausible here
  o.max_frame_rotation_deg = 45;
  return o;
}

class SlambookNoPrior : public testing::TestWithParam<MethodCase> {};

// Without a prior every step (23 to 73 cm) fails for every method, and the failure must be
// reported (lost, pose held), not published as a wrong motion. The overlap check catches the
// wrong local minima: e.g. on the 23 cm forward step 4->5 the icp methods converge ~20 cm short
// with only 46-51 % of the points agreeing (the floor, parallel to the motion, agrees anyway).
TEST_P(SlambookNoPrior, FarStepsAreLostNotWrong) {
  Slambook data;
  if (!data.Load()) GTEST_SKIP() << "shared data missing: " << DataDir() << "/kinect_slambook2_ch5";
  for (int i = 0; i + 1 < 5; ++i) {
    RgbdOdometry odo(FarApartOptions(GetParam()));
    ASSERT_EQ(odo.Process(data.frames[i]).status, TrackingStatus::kInitialised);
    const RgbdOdometryResult r = odo.Process(data.frames[i + 1]);
    const Eigen::Isometry3d truth = data.Truth(i);
    const Error e = Compare(truth, r.world_from_optical);
    std::printf(
        "[ slambook %d->%d ] %-8s scale %.1f, no prior: %s (%s), truth %.0f mm %.1f deg, error "
        "%.0f mm %.1f deg, overlap %.2f\n",
        i + 1, i + 2, GetParam().method.c_str(), GetParam().scale, TrackingStatusName(r.status),
        r.message.c_str(), truth.translation().norm() * 1e3,
        Eigen::AngleAxisd(truth.linear()).angle() / kDeg, e.translation_m * 1e3, e.rotation_deg,
        r.overlap_fraction);
    EXPECT_EQ(r.status, TrackingStatus::kLost);
    EXPECT_TRUE(r.world_from_optical.isApprox(Eigen::Isometry3d::Identity()));
  }
}
INSTANTIATE_TEST_SUITE_P(Methods, SlambookNoPrior, testing::ValuesIn(kAllCases), CaseName);

// With a coarse motion prior (the truth off by 4.1 cm and 2 deg, as an IMU or wheel odometry
// might give) the chain of 5 frames is tracked by the icp methods at full resolution. Every
// tracked step is within 8 cm and 2 deg of the poses in pose.txt (which agree with the depth
// only to a few cm: even the exact truth as prior ends 15 to 60 mm from it); a step that is
// not tracked must be reported lost.
struct PriorCase {
  std::string method;
  double scale;
  int min_tracked;  // of the 4 steps (measured, README)
};
void PrintTo(const PriorCase& c, std::ostream* os) { *os << c.method << " x" << c.scale; }
class SlambookPrior : public testing::TestWithParam<PriorCase> {};

TEST_P(SlambookPrior, TheChainIsTrackedWithinTheTruthsPrecision) {
  Slambook data;
  if (!data.Load()) GTEST_SKIP() << "shared data missing: " << DataDir() << "/kinect_slambook2_ch5";
  RgbdOdometryOptions o = FarApartOptions({GetParam().method, GetParam().scale});
  // Views 25 deg apart share little: the right alignment of 1->2 has only 31 % of its points on
  // the other frame's depth (a wrong local minimum without a prior: 46-51 %, see above), so the
  // overlap check is lowered here and the prior does the work.
  o.min_overlap_fraction = 0.25;
  RgbdOdometry odo(o);
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  offset.translation() = Eigen::Vector3d(0.02, -0.03, 0.02);
  offset.linear() =
      Eigen::AngleAxisd(2.0 * kDeg, Eigen::Vector3d(1, -1, 1).normalized()).toRotationMatrix();
  ASSERT_EQ(odo.Process(data.frames[0]).status, TrackingStatus::kInitialised);
  Eigen::Isometry3d previous = Eigen::Isometry3d::Identity();
  int tracked = 0;
  for (int i = 0; i + 1 < 5; ++i) {
    RgbdFrame f = data.frames[i + 1];
    const Eigen::Isometry3d truth = data.Truth(i);
    f.has_motion_prior = true;
    f.previous_from_rig_prior = RigFromOptical() * truth * offset * RigFromOptical().inverse();
    const RgbdOdometryResult r = odo.Process(f);
    const Error e = Compare(truth, previous.inverse() * r.world_from_optical);
    std::printf(
        "[ slambook %d->%d ] %-8s scale %.1f, prior off 41 mm 2.0 deg: %s, error %.1f mm %.2f deg "
        "%s\n",
        i + 1, i + 2, GetParam().method.c_str(), GetParam().scale, TrackingStatusName(r.status),
        e.translation_m * 1e3, e.rotation_deg, r.message.c_str());
    previous = r.world_from_optical;
    if (r.status == TrackingStatus::kTracking) {
      ++tracked;
      EXPECT_LT(e.translation_m, 0.08) << "step " << i + 1;
      EXPECT_LT(e.rotation_deg, 2.0) << "step " << i + 1;
    } else {
      EXPECT_TRUE(r.status == TrackingStatus::kLost || r.status == TrackingStatus::kReinitialised)
          << TrackingStatusName(r.status);
    }
  }
  EXPECT_GE(tracked, GetParam().min_tracked);
}

INSTANTIATE_TEST_SUITE_P(Methods, SlambookPrior,
                         testing::Values(PriorCase{"icp", 1.0, 4}, PriorCase{"rgbd_icp", 1.0, 4},
                                         PriorCase{"icp", 0.5, 2}, PriorCase{"rgbd_icp", 0.5, 2},
                                         PriorCase{"rgbd", 1.0, 0}, PriorCase{"rgbd", 0.5, 0}),
                         [](const testing::TestParamInfo<PriorCase>& info) {
                           return info.param.method + (info.param.scale == 1.0 ? "_full" : "_half");
                         });

}  // namespace
}  // namespace rgbd_odometry
}  // namespace sarmap
