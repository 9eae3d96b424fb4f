#include "vision_people/ground_estimator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "vision_people/image_frame.h"
#include "vision_people/pcd_frame.h"
#include "vision_people/people_detector.h"
#include "vision_people/synthetic_scene.h"
#include "vision_people/vision_people_options.h"

namespace sarmap {
namespace vision_people {
namespace {

constexpr double kDeg = M_PI / 180;
const std::string kDataDir = SARMAP_DATA_DIR;
// Floor of five_people.pcd as given by PCL's own unit test (camera frame, a x + b y + c z + d = 0).
const Eigen::Vector4d kFivePeopleFloor(-0.0103586, 0.997011, 0.0765573, -1.26614);

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

DetectorOptions DepthOnly() {
  DetectorOptions o;
  o.color.hog = "none";
  return o;
}

// A mounting file wrong by `dh` in height and `dtilt` in tilt.
GroundPlane Wrong(const GroundPlane& truth, double dh, double dtilt) {
  CameraMounting m = MountingFromGround(truth);
  m.height_m += dh;
  m.tilt_down_rad += dtilt;
  return GroundFromCameraMounting(m);
}

TEST(GroundEstimator, MountingRoundTrip) {
  for (double h : {0.3, 1.2}) {
    for (double tilt : {-25.0, 0.0, 12.0}) {
      for (double roll : {-5.0, 0.0, 3.0}) {
        const CameraMounting m{h, tilt * kDeg, roll * kDeg};
        const CameraMounting back = MountingFromGround(GroundFromCameraMounting(m));
        EXPECT_NEAR(back.height_m, h, 1e-12);
        EXPECT_NEAR(back.tilt_down_rad, m.tilt_down_rad, 1e-12);
        EXPECT_NEAR(back.roll_rad, m.roll_rad, 1e-12);
      }
    }
  }
  // The synthetic scene's camera pitched up by 8 degrees is tilted down by -8.
  SyntheticScene scene;
  scene.camera_pitch_rad = 8 * kDeg;
  EXPECT_NEAR(MountingFromGround(scene.ground()).tilt_down_rad, -8 * kDeg, 1e-12);
}

// The mounting options as a user gives them, and robot.yaml's convention (roll_rad = -pi/2 -
// tilt down) as config/robot.yaml documents it.
TEST(GroundEstimator, MountingOptionsAsAUserGivesThem) {
  VisionPeopleOptions o;
  o.camera_height_m = 0.8;
  o.camera_tilt_down_deg = 10;
  o.camera_roll_deg = -3;
  const CameraMounting m = MountingFromGround(InitialGround(o));
  EXPECT_NEAR(m.height_m, 0.8, 1e-12);
  EXPECT_NEAR(m.tilt_down_rad, 10 * kDeg, 1e-12);
  EXPECT_NEAR(m.roll_rad, -3 * kDeg, 1e-12);
  common::ExtrinsicsOptions base_from_camera{0.1, 0.0, 0.6, -M_PI / 2 - 10 * kDeg, 0.0, -M_PI / 2};
  const common::Rigid3d t = base_from_camera.ToRigid3d();
  const CameraMounting r =
      MountingFromGround(GroundFromMounting(t.rotation().toRotationMatrix(), t.translation()));
  EXPECT_NEAR(r.height_m, 0.6, 1e-12);
  EXPECT_NEAR(r.tilt_down_rad, 10 * kDeg, 1e-9);
  EXPECT_NEAR(r.roll_rad, 0.0, 1e-9);
}

// The floor is found from any height 0.3-2 m and tilt +-25 deg with the default mounting
// (0.55 m, level) as the only prior.
TEST(GroundEstimator, FindsTheFloorFromAnyMounting) {
  const GroundPlane prior = SyntheticScene().ground();
  for (double h : {0.3, 0.8, 1.5, 2.0}) {
    for (double pitch_deg : {-25.0, -10.0, 0.0, 10.0, 20.0}) {
      SyntheticScene scene;
      scene.camera_height_m = h;
      scene.camera_pitch_rad = pitch_deg * kDeg;
      scene.back_wall_m = 6.0;
      scene.objects.push_back({SyntheticObject::kTable, 2.5, 0.8, 0.3, 0});
      scene.objects.push_back({SyntheticObject::kCabinet, 3.5, -1.2, 0.0, 0});
      RgbdFrame frame;
      RenderFrame(scene, 7, false, &frame);
      const FloorFit fit =
          FitFloor(frame.xyz.data(), frame.width, frame.height, 0.4, 8.0, GroundOptions(), {prior});
      // Required when the image's bottom row sees the floor within 3 m; otherwise "no floor"
      // is an acceptable answer, a wrong floor is not.
      const double bottom_ray_deg =
          std::atan(scene.intrinsics.cy / scene.intrinsics.fy) / kDeg - pitch_deg;
      const bool required = bottom_ray_deg > std::atan(h / 3.0) / kDeg;
      if (!required && !fit.found) continue;
      ASSERT_TRUE(fit.found) << "height " << h << " pitch " << pitch_deg;
      const GroundPlane truth = scene.ground();
      EXPECT_NEAR(fit.plane.offset, h, std::max(0.03, 0.025 * h))
          << "height " << h << " pitch " << pitch_deg;
      EXPECT_LT(AngleBetweenDeg(fit.plane, truth), 1.0) << "height " << h << " pitch " << pitch_deg;
    }
  }
}

// Looking down at a table top with the floor beside it: the floor wins (nothing is seen under
// a floor), although the table top fits the prior (camera 0.75 m above it) better.
TEST(GroundEstimator, TableTopIsNotTheFloor) {
  SyntheticScene scene;
  scene.camera_height_m = 1.5;
  scene.camera_pitch_rad = -20 * kDeg;
  for (double y : {-0.6, 0.6}) scene.objects.push_back({SyntheticObject::kTable, 2.2, y, 0.0, 0});
  RgbdFrame frame;
  RenderFrame(scene, 3, false, &frame);
  GroundPlane table_prior = scene.ground();
  table_prior.offset -= 0.74;
  const FloorFit fit = FitFloor(frame.xyz.data(), frame.width, frame.height, 0.4, 8.0,
                                GroundOptions(), {table_prior});
  ASSERT_TRUE(fit.found);
  EXPECT_NEAR(fit.plane.offset, 1.5, 0.03);
}

// A wall filling the view: no floor, and the tracker keeps what it had.
TEST(GroundEstimator, NoFloorFacingAWall) {
  SyntheticScene scene;
  scene.camera_pitch_rad = 20 * kDeg;
  scene.back_wall_m = 0.9;
  RgbdFrame frame;
  RenderFrame(scene, 5, false, &frame);
  const FloorFit fit = FitFloor(frame.xyz.data(), frame.width, frame.height, 0.4, 8.0,
                                GroundOptions(), {scene.ground()});
  EXPECT_FALSE(fit.found);
}

TEST(GroundEstimator, TrackerSmoothsResetsAndReportsAMismatch) {
  GroundOptions o;
  const GroundPlane mounting = GroundFromCameraMounting({0.55, 0, 0});
  GroundTracker tracker(o, mounting);
  // No estimate and no track: the mounting file.
  EXPECT_NEAR(tracker.Update(nullptr, 0).offset, 0.55, 1e-12);
  // The camera is really at 0.85 m, tilted down 10 degrees.
  const GroundPlane truth = GroundFromCameraMounting({0.85, 10 * kDeg, 0});
  int64_t t = 0;
  for (int i = 0; i < 10; ++i) {
    GroundPlane noisy = truth;
    noisy.offset += (i % 2 ? 0.01 : -0.01);
    tracker.Update(&noisy, t += 33333);
  }
  EXPECT_NEAR(tracker.tracked().offset, 0.85, 0.01);
  EXPECT_LT(AngleBetweenDeg(tracker.tracked(), truth), 0.01);
  EXPECT_TRUE(tracker.mismatch());
  // Smoothing: one frame 5 cm off moves the track by smoothing x 5 cm.
  GroundPlane off = truth;
  off.offset += 0.05;
  EXPECT_NEAR(tracker.Update(&off, t += 33333).offset - tracker.tracked().offset, 0.0, 1e-12);
  EXPECT_NEAR(tracker.tracked().offset, 0.85 + o.smoothing * 0.05, 0.01);
  EXPECT_FALSE(tracker.last_update_reset());
  // A jump away from the established track and from the mounting file (a box top filling the
  // view) is held off: the track is used, and it restarts only once the jump has lasted
  // reset_confirm_s (another camera).
  const GroundPlane other = GroundFromCameraMounting({1.4, -5 * kDeg, 0});
  EXPECT_NEAR(tracker.Update(&other, t += 33333).offset, tracker.tracked().offset, 1e-12);
  EXPECT_NEAR(tracker.tracked().offset, 0.85 + o.smoothing * 0.05, 0.01);
  EXPECT_TRUE(tracker.last_update_held_off());
  EXPECT_FALSE(tracker.last_update_reset());
  const int64_t jump_start = t;
  while (t - jump_start < static_cast<int64_t>(o.reset_confirm_s * 1e6) - 33333) {
    tracker.Update(&other, t += 33333);
    ASSERT_TRUE(tracker.last_update_held_off());
  }
  EXPECT_EQ(tracker.held_off(), static_cast<int>((t - jump_start) / 33333) + 1);
  EXPECT_NEAR(tracker.Update(&other, t += 33333).offset, 1.4, 1e-12);
  EXPECT_TRUE(tracker.last_update_reset());
  EXPECT_FALSE(tracker.last_update_held_off());
  EXPECT_FALSE(tracker.mismatch());  // not established yet
  // A young track follows a jump at once.
  EXPECT_NEAR(tracker.Update(&truth, t += 33333).offset, 0.85, 1e-12);
  EXPECT_TRUE(tracker.last_update_reset());
  // A gap in time restarts it too; without a fit it then falls back to the mounting file.
  EXPECT_NEAR(tracker.Update(nullptr, t += 10'000'000).offset, 0.55, 1e-12);
  EXPECT_TRUE(tracker.last_update_reset());
}

// On a camera whose mounting file is right, fits of other planes (a box top, a table) that
// interrupt the floor are held off however they differ from each other, and a jump back to the
// mounting file is taken at once.
TEST(GroundEstimator, TrackerHoldsOffOtherPlanesAndReturnsToTheMountingAtOnce) {
  GroundOptions o;
  const GroundPlane mounting = GroundFromCameraMounting({0.55, 0, 0});
  GroundTracker tracker(o, mounting);
  int64_t t = 0;
  for (int i = 0; i < o.established_frames; ++i) tracker.Update(&mounting, t += 66667);
  ASSERT_TRUE(tracker.established());
  const GroundPlane box_top = GroundFromCameraMounting({0.27, -3 * kDeg, 14 * kDeg});
  const GroundPlane table = GroundFromCameraMounting({0.97, 19 * kDeg, 0});
  for (int i = 0; i < 40; ++i) {  // 2.7 s of alternating other planes
    const GroundPlane& other = i % 2 ? box_top : table;
    EXPECT_NEAR(tracker.Update(&other, t += 66667).offset, 0.55, 1e-9) << "frame " << i;
    EXPECT_TRUE(tracker.last_update_held_off());
  }
  EXPECT_EQ(tracker.resets(), 0);
  // With the mounting file wrong, the track is established on the floor the data shows; a
  // jump back to the file's floor is believed at once.
  GroundTracker wrong_file(o, GroundFromCameraMounting({0.85, 10 * kDeg, 0}));
  for (int i = 0; i < o.established_frames; ++i) wrong_file.Update(&mounting, t += 66667);
  ASSERT_TRUE(wrong_file.established());
  const GroundPlane file_floor = GroundFromCameraMounting({0.85, 10 * kDeg, 0});
  EXPECT_NEAR(wrong_file.Update(&file_floor, t += 66667).offset, file_floor.offset, 1e-12);
  EXPECT_TRUE(wrong_file.last_update_reset());
  // Without the hold-off every other plane restarts the track.
  o.reset_confirm_s = 0;
  GroundTracker at_once(o, mounting);
  for (int i = 0; i < o.established_frames; ++i) at_once.Update(&mounting, t += 66667);
  EXPECT_NEAR(at_once.Update(&box_top, t += 66667).offset, box_top.offset, 1e-12);
}

// The mounting file wrong by 0.3 m and 10 degrees (either way): people are still found, the
// floor comes from the data, and the disagreement is reported once the track is established.
TEST(GroundEstimator, WrongMountingFileStillDetectsSynthetic) {
  for (double dh : {-0.3, 0.3}) {
    for (double dtilt : {-10 * kDeg, 10 * kDeg}) {
      SyntheticScene scene;
      scene.camera_height_m = 0.9;
      scene.camera_pitch_rad = -5 * kDeg;
      scene.back_wall_m = 7.0;
      scene.people.push_back({3.2, 0.4, 1.72, 0.5});
      scene.people.push_back({4.5, -1.0, 1.6, 2.0});
      scene.objects.push_back({SyntheticObject::kChair, 2.3, -0.8, 0.4, 0});
      PeopleDetector detector(DepthOnly(), Wrong(scene.ground(), dh, dtilt), nullptr);
      for (int f = 0; f < 6; ++f) {
        RgbdFrame frame;
        RenderFrame(scene, 11 + f, false, &frame);
        frame.utime = f * 33333;
        const DetectionResult r = detector.Detect(frame);
        EXPECT_EQ(r.people.size(), 2u) << "dh " << dh << " dtilt " << dtilt << " frame " << f;
        EXPECT_NEAR(r.camera.height_m, 0.9, 0.03);
        EXPECT_NEAR(r.camera.tilt_down_rad, 5 * kDeg, 1 * kDeg);
        if (f == 5) {
          EXPECT_TRUE(r.stats.mounting_mismatch);
        }
      }
    }
  }
}

TEST(GroundEstimator, WrongMountingFileStillDetectsFivePeople) {
  const std::string path = kDataDir + "/vision/pcl_people/five_people.pcd";
  if (!Exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  RgbdFrame frame;
  std::string error;
  ASSERT_TRUE(LoadPcdFrame(path, PinholeIntrinsics(), &frame, &error)) << error;
  const GroundPlane truth = GroundPlane::FromCoefficients(kFivePeopleFloor);
  // The config/robot.yaml default (0.55 m, level: 0.7 m and 4 degrees off) and the true
  // mounting 0.3 m / 10 degrees off either way; colour and depth alone.
  std::vector<GroundPlane> files = {GroundFromCameraMounting({0.55, 0, 0})};
  for (double dh : {-0.3, 0.3}) {
    for (double dtilt : {-10 * kDeg, 10 * kDeg}) files.push_back(Wrong(truth, dh, dtilt));
  }
  for (const GroundPlane& file : files) {
    for (bool color : {true, false}) {
      DetectorOptions o;
      if (!color) o.color.hog = "none";
      PeopleDetector detector(o, file, MakeHogClassifier(o.color));
      const DetectionResult r = detector.Detect(frame, &error);
      EXPECT_EQ(r.people.size(), 5u) << "file height " << file.offset << " colour " << color;
      EXPECT_NEAR(r.ground.offset, truth.offset, 0.04);
      EXPECT_LT(AngleBetweenDeg(r.ground, truth), 1.0);
    }
  }
}

// Unrelated frames one after another (an image folder): each frame's floor is its own.
TEST(GroundEstimator, FloorDoesNotCarryOverBetweenUnrelatedFrames) {
  PeopleDetector detector(DepthOnly(), GroundFromCameraMounting({0.55, 0, 0}), nullptr);
  for (int f = 0; f < 6; ++f) {
    SyntheticScene scene;
    scene.camera_height_m = f % 2 ? 1.4 : 0.45;
    scene.camera_pitch_rad = (f % 2 ? -15 : 5) * kDeg;
    scene.people.push_back({3.5, 0.0, 1.7, 0.0});
    RgbdFrame frame;
    RenderFrame(scene, 20 + f, false, &frame);
    frame.utime = f * 100000;
    const DetectionResult r = detector.Detect(frame);
    EXPECT_NEAR(r.ground.offset, scene.camera_height_m, 0.03) << "frame " << f;
    EXPECT_LT(AngleBetweenDeg(r.ground, scene.ground()), 1.0) << "frame " << f;
    EXPECT_EQ(r.people.size(), 1u) << "frame " << f;
  }
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
