#include "vision_people/people_detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>

#include "vision_people/hog_classifier.h"
#include "vision_people/pcd_frame.h"
#include "vision_people/synthetic_scene.h"

namespace sarmap {
namespace vision_people {
namespace {

const std::string kPclDir = std::string(SARMAP_DATA_DIR) + "/vision/pcl_people";
// Floor of five_people.pcd as given by PCL's own unit test (camera frame, a x + b y + c z + d = 0).
const Eigen::Vector4d kFivePeopleFloor(-0.0103586, 0.997011, 0.0765573, -1.26614);

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

void Print(const DetectionResult& r) {
  for (const auto* list : {&r.people, &r.rejected}) {
    for (const auto& c : *list) printf("  %s\n", DescribeCandidate(c).c_str());
  }
}

DetectorOptions DepthOnly() {
  DetectorOptions o;
  o.color.hog = "none";
  return o;
}

// Detections matched to people (closest first, within 0.5 m on the floor); returns matches
// and counts false positives.
int Match(const SyntheticScene& scene, const std::vector<PersonCandidate>& people,
          int* false_positives, double* worst_error_m = nullptr,
          const std::vector<bool>* required = nullptr) {
  std::vector<bool> used(scene.people.size(), false);
  int matched = 0;
  *false_positives = 0;
  if (worst_error_m) *worst_error_m = 0;
  for (const auto& d : people) {
    double best = 0.5;
    int best_i = -1;
    for (size_t i = 0; i < scene.people.size(); ++i) {
      if (used[i]) continue;
      const Eigen::Vector3d truth = scene.PersonInCamera(scene.people[i]);
      const double e =
          std::hypot(truth.x() - d.position_camera.x(), truth.z() - d.position_camera.z());
      if (e < best) {
        best = e;
        best_i = static_cast<int>(i);
      }
    }
    if (best_i < 0) {
      ++*false_positives;
    } else {
      used[best_i] = true;
      if (required && !(*required)[best_i]) continue;  // found a partly hidden person: fine
      ++matched;
      if (worst_error_m) *worst_error_m = std::max(*worst_error_m, best);
    }
  }
  return matched;
}

TEST(GroundPlane, FromMountingOfALevelKinect) {
  // config/robot.yaml: camera 0.55 m up, optical frame z forward, x right, y down.
  SyntheticScene scene;
  const GroundPlane g = scene.ground();
  EXPECT_NEAR(g.normal.x(), 0.0, 1e-12);
  EXPECT_NEAR(g.normal.y(), -1.0, 1e-12);
  EXPECT_NEAR(g.normal.z(), 0.0, 1e-12);
  EXPECT_NEAR(g.offset, 0.55, 1e-12);
  EXPECT_NEAR(g.Height(Eigen::Vector3d(1, 0.55, 3)), 0.0, 1e-12);  // a floor point
  // Tilted up by 8 degrees (Sales 2014): a point 1 m ahead on the floor is still at height 0.
  scene.camera_pitch_rad = 8 * M_PI / 180;
  const GroundPlane t = scene.ground();
  const Eigen::Vector3d floor_point =
      scene.world_R_camera().transpose() * (Eigen::Vector3d(1, 0, 0) - scene.world_t_camera());
  EXPECT_NEAR(t.Height(floor_point), 0.0, 1e-12);
  // PCL's coefficient convention (normal pointing down) is flipped to ours.
  const GroundPlane p = GroundPlane::FromCoefficients(kFivePeopleFloor);
  EXPECT_LT(p.normal.y(), -0.99);
  EXPECT_NEAR(p.offset, 1.266, 0.01);
}

TEST(PeopleDetector, OneSyntheticPersonDepthOnlyWithCovariance) {
  SyntheticScene scene;
  scene.people.push_back({3.0, 0.3, 1.75, 0.0});
  RgbdFrame frame;
  RenderFrame(scene, 1, false, &frame);
  PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
  std::string error;
  const DetectionResult r = detector.Detect(frame, &error);
  EXPECT_TRUE(error.empty()) << error;
  Print(r);
  ASSERT_EQ(r.people.size(), 1u);
  const PersonCandidate& c = r.people[0];
  EXPECT_TRUE(c.depth_only);
  EXPECT_TRUE(r.stats.ground_refined);
  EXPECT_NEAR(r.ground.offset, 0.55, 0.02);
  EXPECT_NEAR(c.height_m, 1.75, 0.08);
  // The centroid of the visible surface lies in front of the body axis by at most ~0.15 m.
  const Eigen::Vector3d truth = scene.PersonInCamera(scene.people[0]);
  EXPECT_NEAR(c.position_camera.x(), truth.x(), 0.1);
  EXPECT_NEAR(c.position_camera.z(), truth.z(), 0.2);
  // Covariance: along the ray (c z^2)^2 + body^2, across pixel noise + body^2.
  const double z = c.position_camera.z();
  const Eigen::Vector3d u = c.position_camera.normalized();
  const double along = u.dot(c.covariance * u);
  const double expected = std::pow(0.0015 * z * z, 2) + 0.08 * 0.08;
  EXPECT_NEAR(along, expected, 1e-9);
  EXPECT_GT(along, c.covariance.trace() / 3 - 1e-12);  // depth is the noisiest direction
}

// The camera sees a body's near side: the position is moved (pi/8) x body thickness beyond the
// visible surface's centroid, away from the camera along the floor, and lands nearer the body's
// axis than the centroid does.
TEST(PeopleDetector, PositionIsTheBodyCentreBehindTheVisibleSurface) {
  SyntheticScene scene;
  scene.people.push_back({3.0, 0.6, 1.75, 0.0});
  RgbdFrame frame;
  RenderFrame(scene, 1, false, &frame);
  DetectorOptions centroid_only = DepthOnly();
  centroid_only.noise.body_thickness_m = 0;
  DetectorOptions body = DepthOnly();
  body.noise.body_thickness_m = 0.25;
  const DetectionResult a = PeopleDetector(centroid_only, scene.ground(), nullptr).Detect(frame);
  const DetectionResult b = PeopleDetector(body, scene.ground(), nullptr).Detect(frame);
  ASSERT_EQ(a.people.size(), 1u);
  ASSERT_EQ(b.people.size(), 1u);
  const GroundPlane floor = scene.ground();
  auto on_floor = [&](const Eigen::Vector3d& p) {  // drop onto the floor plane
    return (p - floor.Height(p) * floor.normal).eval();
  };
  const Eigen::Vector3d pa = on_floor(a.people[0].position_camera);
  const Eigen::Vector3d pb = on_floor(b.people[0].position_camera);
  const Eigen::Vector3d foot = on_floor(Eigen::Vector3d::Zero());  // below the camera
  EXPECT_NEAR((pb - pa).norm(), M_PI / 8 * 0.25, 2e-3);
  EXPECT_NEAR((pb - pa).normalized().dot((pa - foot).normalized()), 1.0, 1e-3)
      << "away from the camera along the line of sight";
  const Eigen::Vector3d truth = on_floor(scene.PersonInCamera(scene.people[0]));
  EXPECT_LT((pb - truth).norm(), (pa - truth).norm());
}

// Facing a wall with little floor in view, the bottom rows of the wall lie in the floor band;
// they must not tilt the fit, or the tilt grows frame by frame through the prior (the
// simulated lab's floor drifted 8 degrees this way).
TEST(PeopleDetector, FloorDoesNotDriftFacingAWall) {
  SyntheticScene scene;
  scene.back_wall_m = 2.2;
  PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
  const GroundPlane truth = scene.ground();
  double worst_tilt_deg = 0, worst_offset_m = 0;
  int refined = 0;
  for (uint32_t seed = 1; seed <= 30; ++seed) {
    RgbdFrame frame;
    RenderFrame(scene, seed, false, &frame);
    const DetectionResult r = detector.Detect(frame);
    refined += r.stats.ground_refined;
    worst_tilt_deg = std::max(
        worst_tilt_deg, std::acos(std::min(1.0, r.ground.normal.dot(truth.normal))) * 180.0 / M_PI);
    worst_offset_m = std::max(worst_offset_m, std::abs(r.ground.offset - truth.offset));
  }
  printf(
      "facing a wall at 2.2 m: %d/30 frames refined, worst tilt %.2f deg, worst height error %.3f "
      "m\n",
      refined, worst_tilt_deg, worst_offset_m);
  EXPECT_GT(refined, 0);
  EXPECT_LT(worst_tilt_deg, 1.0);
  EXPECT_LT(worst_offset_m, 0.02);
}

TEST(PeopleDetector, HeadBasedSubclusteringSplitsTwoPeopleSideBySide) {
  SyntheticScene scene;
  // Shoulder to shoulder, 0.45 m apart: one Euclidean cluster, two heads.
  scene.people.push_back({3.5, -0.225, 1.80, 0.0});
  scene.people.push_back({3.5, 0.225, 1.65, 0.0});
  RgbdFrame frame;
  RenderFrame(scene, 2, false, &frame);
  PeopleDetector detector(DepthOnly(), scene.ground(), nullptr);
  const DetectionResult r = detector.Detect(frame);
  int fp = 0;
  EXPECT_EQ(Match(scene, r.people, &fp), 2);
  EXPECT_EQ(fp, 0);
}

TEST(PeopleDetector, FurnitureIsNotAPersonInTheDark) {
  SyntheticScene scene;
  scene.objects.push_back({SyntheticObject::kChair, 2.0, 0.6, 0.3});
  scene.objects.push_back({SyntheticObject::kTable, 3.5, -0.8, 0.0});
  scene.objects.push_back({SyntheticObject::kCabinet, 4.5, 1.2, 0.0});
  scene.objects.push_back({SyntheticObject::kPole, 2.8, -0.4, 0.0});
  scene.objects.push_back({SyntheticObject::kBox, 3.0, 0.9, 0.4, 1.5});
  scene.back_wall_m = 6.0;
  RgbdFrame frame;
  RenderFrame(scene, 3, true, &frame);
  PeopleDetector detector(DetectorOptions(), scene.ground(), MakeOpenCvHogClassifier());
  const DetectionResult r = detector.Detect(frame);
  EXPECT_EQ(r.stats.color_state, ColorState::kDark);
  EXPECT_EQ(r.people.size(), 0u);
  for (const auto& c : r.rejected) EXPECT_TRUE(c.depth_only);
}

// Stand-in for the simulated lab in the dark (the simulator is not available yet): random
// rooms with 1-3 people and furniture, a black colour image, depth only.
TEST(PeopleDetector, SyntheticDarkLabFrameRecallFromDepthAlone) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> U(0, 1);
  PeopleDetector detector(DetectorOptions(), SyntheticScene().ground(), MakeOpenCvHogClassifier());
  int visible = 0, found = 0, false_positives = 0, frames = 0;
  double worst = 0;
  std::string misses;  // frames with a miss or a false positive
  for (int room = 0; room < 12; ++room) {
    SyntheticScene scene;
    scene.camera_pitch_rad = (U(rng) - 0.5) * 0.1;
    scene.back_wall_m = 6.5 + U(rng);
    const int n = 1 + room % 3;
    for (int i = 0; i < n; ++i) {
      // Spread across the view, 1.8..5.5 m away, 1.0 m apart at least.
      for (int attempt = 0; attempt < 50; ++attempt) {
        SyntheticPerson p{1.8 + 3.7 * U(rng), 0, 1.5 + 0.4 * U(rng), 2 * M_PI * U(rng)};
        p.y_m = (U(rng) - 0.5) * 2 * 0.35 * p.x_m;  // inside +-19 degrees
        bool ok = true;
        for (const auto& q : scene.people)
          ok = ok && std::hypot(p.x_m - q.x_m, p.y_m - q.y_m) > 1.0;
        if (ok) {
          scene.people.push_back(p);
          break;
        }
      }
    }
    const SyntheticObject::Kind kinds[] = {SyntheticObject::kChair, SyntheticObject::kTable,
                                           SyntheticObject::kCabinet, SyntheticObject::kPole,
                                           SyntheticObject::kBox};
    for (int i = 0; i < 2; ++i) {
      for (int attempt = 0; attempt < 50; ++attempt) {
        SyntheticObject o{kinds[(room + i) % 5], 1.8 + 4.0 * U(rng), 0, U(rng) * M_PI, 0};
        o.y_m = (U(rng) - 0.5) * 2 * 0.4 * o.x_m;
        bool ok = true;
        for (const auto& q : scene.people)
          ok = ok && std::hypot(o.x_m - q.x_m, o.y_m - q.y_m) > 1.2;
        if (ok) {
          scene.objects.push_back(o);
          break;
        }
      }
    }
    // Visible: head and feet in view and at least 70 % of the body unoccluded.
    std::vector<bool> required(scene.people.size());
    int num_required = 0;
    for (size_t i = 0; i < scene.people.size(); ++i) {
      required[i] = scene.VisibleFraction(i) >= 0.7;
      num_required += required[i];
    }
    detector.ResetGround();
    for (int f = 0; f < 2; ++f) {
      RgbdFrame frame;
      RenderFrame(scene, 100 * room + f, true, &frame);
      const DetectionResult r = detector.Detect(frame);
      ASSERT_EQ(r.stats.color_state, ColorState::kDark);
      int fp = 0;
      double err = 0;
      const int m = Match(scene, r.people, &fp, &err, &required);
      if (m < num_required || fp > 0) {  // what the detector got wrong, shown on failure
        char line[160];
        snprintf(line, sizeof(line), "room %d frame %d: %d/%zu found, %d fp; truth:", room, f, m,
                 scene.people.size(), fp);
        misses += line;
        for (const auto& p : scene.people) {
          const Eigen::Vector3d t = scene.PersonInCamera(p);
          snprintf(line, sizeof(line), " (%.2f %.2f %.2f H %.2f yaw %.1f vis %.2f)", t.x(), t.y(),
                   t.z(), p.height_m, p.yaw_rad, scene.VisibleFraction(&p - &scene.people[0]));
          misses += line;
        }
        misses += "\n";
      }
      found += m;
      worst = std::max(worst, err);
      false_positives += fp;
      visible += num_required;
      ++frames;
    }
  }
  const double recall = static_cast<double>(found) / visible;
  const double fp_per_frame = static_cast<double>(false_positives) / frames;
  printf(
      "synthetic dark lab: %d frames, frame recall %.3f (%d/%d), %.3f false positives/frame, "
      "worst floor error %.2f m\n",
      frames, recall, found, visible, fp_per_frame, worst);
  EXPECT_GE(recall, 0.8) << misses;  // the dark goal
  // Depth alone can still confuse furniture with a person (here a 1.2 m pillar box at 4.7 m,
  // partly hidden by a person in front): measured 0.083 false positives per frame (2 in 24);
  // pinned so it cannot get worse unnoticed.
  EXPECT_LE(fp_per_frame, 0.1) << misses;
}

TEST(PeopleDetector, FivePeopleWithColour) {
  const std::string path = kPclDir + "/five_people.pcd";
  if (!Exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  RgbdFrame frame;
  std::string error;
  ASSERT_TRUE(LoadPcdFrame(path, PinholeIntrinsics(), &frame, &error)) << error;
  ASSERT_TRUE(frame.has_color());
  for (const char* hog : {"opencv", "pcl"}) {
    DetectorOptions o;
    o.color.hog = hog;
    o.color.pcl_svm_file = kPclDir + "/trainedLinearSVMForPeopleDetectionWithHOG.yaml";
    if (std::string(hog) == "pcl") o.color.hog_threshold = -1.5;  // PCL's own min_confidence
    PeopleDetector detector(o, GroundPlane::FromCoefficients(kFivePeopleFloor),
                            MakeHogClassifier(o.color));
    const DetectionResult r = detector.Detect(frame, &error);
    EXPECT_TRUE(error.empty()) << error;
    EXPECT_EQ(r.stats.color_state, ColorState::kUsable);
    EXPECT_TRUE(r.stats.ground_refined);
    ASSERT_EQ(r.people.size(), 5u) << hog;
    for (const auto& c : r.people) {
      EXPECT_TRUE(c.hog_used);
      EXPECT_GT(c.height_m, 1.6);
      EXPECT_LT(c.height_m, 1.9);
      printf("%s: person at (%.2f %.2f %.2f) height %.2f hog %.2f depth %.2f confidence %.2f\n",
             hog, c.position_camera.x(), c.position_camera.y(), c.position_camera.z(), c.height_m,
             c.hog_score, c.depth_score, c.confidence);
    }
  }
}

TEST(PeopleDetector, FivePeopleFromDepthAlone) {
  const std::string path = kPclDir + "/five_people.pcd";
  if (!Exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  RgbdFrame frame;
  std::string error;
  ASSERT_TRUE(LoadPcdFrame(path, PinholeIntrinsics(), &frame, &error)) << error;
  // Darken the colour to 5 % (a room with the lights off): the detector must switch to depth.
  for (auto& b : frame.rgb) b = static_cast<uint8_t>(b / 20);
  PeopleDetector detector(DetectorOptions(), GroundPlane::FromCoefficients(kFivePeopleFloor),
                          MakeOpenCvHogClassifier());
  const DetectionResult r = detector.Detect(frame, &error);
  EXPECT_EQ(r.stats.color_state, ColorState::kDark);
  EXPECT_EQ(r.people.size(), 5u);
  for (const auto& c : r.people) EXPECT_TRUE(c.depth_only);
}

TEST(PeopleDetector, GlareAndFlatColourFallBackToDepth) {
  const std::string path = kPclDir + "/five_people.pcd";
  if (!Exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  RgbdFrame frame;
  std::string error;
  ASSERT_TRUE(LoadPcdFrame(path, PinholeIntrinsics(), &frame, &error)) << error;
  PeopleDetector detector(DetectorOptions(), GroundPlane::FromCoefficients(kFivePeopleFloor),
                          MakeOpenCvHogClassifier());
  RgbdFrame glare = frame;  // sunlight into the lens: almost everything saturated
  for (size_t i = 0; i < glare.rgb.size(); ++i) glare.rgb[i] = i % 97 == 0 ? 200 : 255;
  DetectionResult r = detector.Detect(glare, &error);
  EXPECT_EQ(r.stats.color_state, ColorState::kGlare);
  EXPECT_EQ(r.people.size(), 5u);
  RgbdFrame flat = frame;  // fog / smoke: mid grey, no contrast
  for (auto& b : flat.rgb) b = static_cast<uint8_t>(120 + b % 5);
  r = detector.Detect(flat, &error);
  EXPECT_EQ(r.stats.color_state, ColorState::kLowContrast);
  EXPECT_EQ(r.people.size(), 5u);
  for (const auto& c : r.people) EXPECT_TRUE(c.depth_only);
}

TEST(PeopleDetector, HeadAndShouldersOnlyIsNoPerson) {
  const std::string path = kPclDir + "/pcl_data_person/person.pcd";
  if (!Exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  RgbdFrame frame;
  std::string error;
  ASSERT_TRUE(LoadPcdFrame(path, PinholeIntrinsics(), &frame, &error)) << error;
  EXPECT_FALSE(frame.has_color());
  // The floor is not in view; whatever the mounting, nothing may fire.
  std::vector<GroundPlane> floors = {GroundPlane::FromCoefficients(kFivePeopleFloor),
                                     SyntheticScene().ground()};
  for (double h : {0.8, 1.0, 1.2, 1.5, 1.8}) {
    floors.push_back(GroundPlane::FromCoefficients(Eigen::Vector4d(0, 1, 0, -h)));
  }
  for (const auto& floor : floors) {
    PeopleDetector detector(DetectorOptions(), floor, MakeOpenCvHogClassifier());
    const DetectionResult r = detector.Detect(frame, &error);
    EXPECT_EQ(r.people.size(), 0u) << "floor " << floor.offset << " m below the camera";
  }
}

TEST(PeopleDetector, BadFramesGiveAnErrorNotACrash) {
  PeopleDetector detector(DetectorOptions(), SyntheticScene().ground(), MakeOpenCvHogClassifier());
  std::string error;
  RgbdFrame empty;
  EXPECT_TRUE(detector.Detect(empty, &error).people.empty());
  EXPECT_NE(error.find("empty"), std::string::npos) << error;

  RgbdFrame nan;
  nan.width = 640;
  nan.height = 480;
  nan.xyz.assign(640 * 480 * 3, std::numeric_limits<float>::quiet_NaN());
  nan.rgb.assign(640 * 480 * 3, 128);
  EXPECT_TRUE(detector.Detect(nan, &error).people.empty());
  EXPECT_NE(error.find("no finite depth"), std::string::npos) << error;

  RgbdFrame wrong = nan;
  wrong.xyz.resize(100);
  EXPECT_TRUE(detector.Detect(wrong, &error).people.empty());
  EXPECT_FALSE(error.empty());

  // Colour of the wrong size: a warning, and the depth path still finds the person.
  SyntheticScene scene;
  scene.people.push_back({3.0, 0.0, 1.7, 0.0});
  RgbdFrame frame;
  RenderFrame(scene, 5, false, &frame);
  frame.rgb.assign(320 * 240 * 3, 100);
  const DetectionResult r = detector.Detect(frame, &error);
  EXPECT_NE(error.find("colour"), std::string::npos) << error;
  EXPECT_EQ(r.people.size(), 1u);
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
