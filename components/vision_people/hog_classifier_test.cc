#include "vision_people/hog_classifier.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace sarmap {
namespace vision_people {
namespace {

const std::string kRgbDir = std::string(SARMAP_DATA_DIR) + "/vision/rgb";
// TUD-Campus measured (aspect-standardised IoU >= 0.5): precision 0.797, recall 0.591.
constexpr double kPrecisionFloor = 0.78;
constexpr double kRecallFloor = 0.57;

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

std::vector<ImageBox> Standardized(std::vector<ImageBox> boxes) {
  for (auto& b : boxes) b = StandardizeAspect(b);
  return boxes;
}

TEST(HogClassifier, BoxIoU) {
  ImageBox a{0, 0, 10, 10, 0}, b{5, 0, 10, 10, 0};
  EXPECT_NEAR(BoxIoU(a, b), 50.0 / 150.0, 1e-12);
  EXPECT_NEAR(BoxIoU(a, a), 1.0, 1e-12);
  ImageBox far{100, 100, 1, 1, 0};
  EXPECT_EQ(BoxIoU(a, far), 0.0);
  std::vector<bool> found;
  EXPECT_EQ(MatchBoxes({a, b, far}, {a}, 0.5, &found), 1);
  EXPECT_TRUE(found[0]);
}

TEST(HogClassifier, PclSvmFileLoadsAndBadFileThrows) {
  const std::string path = std::string(SARMAP_DATA_DIR) +
                           "/vision/pcl_people/trainedLinearSVMForPeopleDetectionWithHOG.yaml";
  if (!Exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  EXPECT_NO_THROW(MakePclHogClassifier(path));
  EXPECT_THROW(MakePclHogClassifier("/nonexistent.yaml"), std::runtime_error);
}

TEST(HogClassifier, InriaSamplesEveryBoxedPersonFound) {
  for (const std::string name : {"crop001501", "crop_000001"}) {
    const std::string image_path = kRgbDir + "/inria_samples/" + name + ".png";
    if (!Exists(image_path)) GTEST_SKIP() << "shared data missing: " << image_path;
    std::vector<uint8_t> rgb;
    int w = 0, h = 0;
    ASSERT_TRUE(ReadRgbImage(image_path, &rgb, &w, &h));
    const auto truth = ReadPascalBoxes(kRgbDir + "/inria_samples/" + name + ".txt");
    ASSERT_FALSE(truth.empty());
    const auto found = DetectPeopleInImage(rgb.data(), w, h, SlidingWindowOptions());
    std::vector<bool> hit;
    const int tp_raw = MatchBoxes(found, truth, 0.5);
    const int tp = MatchBoxes(Standardized(found), Standardized(truth), 0.5, &hit);

    printf("INRIA %s: %d/%zu boxed people found (IoU >= 0.5 on aspect-standardised boxes; %d with raw "
           "boxes), %zu detections\n", name.c_str(), tp, truth.size(), tp_raw, found.size());
    EXPECT_EQ(tp, static_cast<int>(truth.size())) << name;
  }
}

// Precision and recall of the HOG stage (OpenCV's INRIA people detector, sliding window)
// against TUD-Campus gt/gt.txt, PASCAL criterion IoU >= 0.5.
TEST(HogClassifier, TudCampusPrecisionRecall) {
  const std::string dir = kRgbDir + "/tud_campus";
  if (!Exists(dir + "/gt/gt.txt")) GTEST_SKIP() << "shared data missing: " << dir;
  std::map<int, std::vector<ImageBox>> truth;
  std::ifstream gt(dir + "/gt/gt.txt");
  std::string line;
  int total_truth = 0;
  while (std::getline(gt, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream in(line);
    int frame, id;
    ImageBox b;
    if (in >> frame >> id >> b.x >> b.y >> b.w >> b.h) {
      truth[frame].push_back(b);
      ++total_truth;
    }
  }
  ASSERT_GT(total_truth, 300);
  int tp = 0, tp_raw = 0, detections = 0, frames = 0;
  for (int f = 1;; ++f) {
    char name[64];
    snprintf(name, sizeof(name), "/img1/%06d.jpg", f);
    std::vector<uint8_t> rgb;
    int w = 0, h = 0;
    if (!ReadRgbImage(dir + name, &rgb, &w, &h)) break;
    ++frames;
    const auto found = DetectPeopleInImage(rgb.data(), w, h, SlidingWindowOptions());
    detections += static_cast<int>(found.size());
    tp += MatchBoxes(Standardized(found), Standardized(truth[f]), 0.5);
    tp_raw += MatchBoxes(found, truth[f], 0.5);
  }
  const double precision = detections ? static_cast<double>(tp) / detections : 0.0;
  const double recall = static_cast<double>(tp) / total_truth;
  printf("TUD-Campus HOG stage: %d frames, %d ground-truth boxes, %d detections, %d true positives "
         "(IoU >= 0.5, aspect-standardised boxes): precision %.3f recall %.3f; raw boxes: precision %.3f "
         "recall %.3f\n", frames, total_truth, detections, tp, precision, recall,
         detections ? static_cast<double>(tp_raw) / detections : 0.0, static_cast<double>(tp_raw) / total_truth);
  EXPECT_EQ(frames, 71);
  // Floors pinned just below the measured figures.
  EXPECT_GE(precision, kPrecisionFloor);
  EXPECT_GE(recall, kRecallFloor);
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
