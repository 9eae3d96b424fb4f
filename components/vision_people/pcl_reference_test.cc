// Our detector against PCL's own GroundBasedPeopleDetectionApp on five_people.pcd: the same
// 5 people, each of ours within 0.2 m (on the floor) of PCL's cluster centre.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "vision_people/hog_classifier.h"
#include "vision_people/pcd_frame.h"
#include "vision_people/pcl_reference.h"
#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {
namespace {

TEST(PclReference, FivePeopleEachWithinTwentyCentimetresOfPclsCluster) {
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/vision/pcl_people";
  if (!std::ifstream(dir + "/five_people.pcd").good()) GTEST_SKIP() << "shared data missing: " << dir;
  RgbdFrame frame;
  std::string error;
  ASSERT_TRUE(LoadPcdFrame(dir + "/five_people.pcd", PinholeIntrinsics(), &frame, &error)) << error;
  // The settings of PCL's own unit test (test_people_groundBasedPeopleDetectionApp.cpp).
  const Eigen::Vector4d floor(-0.0103586, 0.997011, 0.0765573, -1.26614);
  PclReferenceOptions ref;
  ref.svm_file = dir + "/trainedLinearSVMForPeopleDetectionWithHOG.yaml";
  std::vector<PclReferencePerson> theirs;
  ASSERT_TRUE(RunPclReference(frame, floor, ref, &theirs, &error)) << error;
  for (const auto& p : theirs) {
    printf("PCL: person at (%.2f %.2f %.2f) height %.2f confidence %.2f\n", p.centroid_camera.x(),
           p.centroid_camera.y(), p.centroid_camera.z(), p.height_m, p.confidence);
  }
  EXPECT_EQ(theirs.size(), 5u);  // PCL's own expectation

  PeopleDetector detector(DetectorOptions(), GroundPlane::FromCoefficients(floor), MakeOpenCvHogClassifier());
  const DetectionResult ours = detector.Detect(frame, &error);
  ASSERT_EQ(ours.people.size(), 5u);
  const GroundPlane g = ours.ground;
  auto on_floor = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return p - g.normal * g.Height(p); };
  std::vector<bool> used(theirs.size(), false);
  for (const auto& c : ours.people) {
    double best = 1e9;
    int best_j = -1;
    for (size_t j = 0; j < theirs.size(); ++j) {
      const double d = (on_floor(c.position_camera) - on_floor(theirs[j].centroid_camera)).norm();
      if (!used[j] && d < best) {
        best = d;
        best_j = static_cast<int>(j);
      }
    }
    ASSERT_GE(best_j, 0);
    used[best_j] = true;
    printf("ours (%.2f %.2f %.2f) height %.2f -> PCL cluster %d: %.3f m apart on the floor, heights differ %.3f m\n",
           c.position_camera.x(), c.position_camera.y(), c.position_camera.z(), c.height_m, best_j, best,
           c.height_m - theirs[best_j].height_m);
    EXPECT_LT(best, 0.2);
  }
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
