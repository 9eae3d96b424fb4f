// OpenCV's default HOG people detector must find the visible people in the lit lab's
// rendered (and JPEG-coded, as published) colour frames.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include "common/image_codec.h"
#include "sim/simulator.h"

namespace sarmap {
namespace sim {
namespace {

struct NullSink : SimSink {
  void Publish(const std::string&, const sarmap::odometry_t&) override {}
  void Publish(const std::string&, const sarmap::image_t&) override {}
  void Publish(const std::string&, const sarmap::audio_frame_t&) override {}
  void Publish(const std::string&, const sarmap::sim_truth_t&) override {}
  void Publish(const std::string&, const sarmap::occupancy_grid_t&) override {}
};

TEST(SimHogTest, DefaultPeopleDetectorFindsVisiblePeopleInLitLab) {
  const std::string tud = std::string(SARMAP_DATA_DIR) + "/vision/rgb/tud_campus/gt/gt.txt";
  if (!std::filesystem::exists(tud)) GTEST_SKIP() << "shared data missing: " << tud;
  SimOptions options;
  options.world = std::string(SARMAP_SOURCE_DIR) + "/config/worlds/lab_lit.yaml";
  options.robot_config = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  options.data_dir = SARMAP_DATA_DIR;
  options.audio.enabled = false;
  Simulator sim(LoadSetup(options, ""));
  ASSERT_TRUE(sim.warnings().empty()) << sim.warnings()[0];

  cv::HOGDescriptor hog;
  hog.setSVMDetector(cv::HOGDescriptor::getDefaultPeopleDetector());
  NullSink sink;
  int expected = 0, found = 0;
  // Frames along the first seconds of the scripted path (the robot drives towards the people).
  for (double t : {0.0, 1.0, 2.0, 3.0, 4.0}) {
    sim.AdvanceTo(t, &sink);
    const Simulator::View view = sim.RenderView();
    sarmap::header_t header;
    sarmap::camera_intrinsics_t intrinsics{};
    const sarmap::image_t jpeg = common::MakeColorImage(
        header, intrinsics, view.rgb.data(), view.width, view.height, options.camera.jpeg_quality);
    std::vector<uint8_t> rgb;
    std::string error;
    ASSERT_TRUE(common::DecodeColorImage(jpeg, &rgb, &error)) << error;
    cv::Mat image(view.height, view.width, CV_8UC3, rgb.data());
    cv::Mat bgr;
    cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
    std::vector<cv::Rect> detections;
    std::vector<double> weights;
    hog.detectMultiScale(bgr, detections, weights, 0.0, cv::Size(8, 8), cv::Size(16, 16), 1.05,
                         2.0);
    for (size_t k = 0; k < sim.world().people.size(); ++k) {
      const Person& person = sim.world().people[k];
      const auto& box = view.person_box[k];
      // A standing person whose whole body is in the frame (the detector needs the full figure).
      const bool whole = view.person_pixels[k] > 800 && box[1] > 2 && box[3] < view.height - 3 &&
                         box[0] > 2 && box[2] < view.width - 3;
      if (person.posture != Posture::kStanding || !whole) continue;
      ++expected;
      const cv::Point centre((box[0] + box[2]) / 2, (box[1] + box[3]) / 2);
      const int body_h = box[3] - box[1];
      bool hit = false;
      for (const cv::Rect& r : detections) {
        hit = hit || (r.contains(centre) && r.height > 0.8 * body_h && r.height < 2.0 * body_h);
      }
      found += hit;
      EXPECT_TRUE(hit) << person.name << " at t=" << t << " not detected (body box " << box[0]
                       << "," << box[1] << " - " << box[2] << "," << box[3] << ", "
                       << detections.size() << " detections)";
    }
  }
  std::printf("HOG: %d of %d visible standing people detected\n", found, expected);
  EXPECT_GE(expected, 6);
}

// In darkness (Sales 2014 §5.2.2) the same detector finds nobody: the colour image is noise.
TEST(SimHogTest, NobodyIsFoundInTheDarkLab) {
  const std::string tud = std::string(SARMAP_DATA_DIR) + "/vision/rgb/tud_campus/gt/gt.txt";
  if (!std::filesystem::exists(tud)) GTEST_SKIP() << "shared data missing: " << tud;
  SimOptions options;
  options.world = std::string(SARMAP_SOURCE_DIR) + "/config/worlds/lab_dark.yaml";
  options.robot_config = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  options.data_dir = SARMAP_DATA_DIR;
  options.audio.enabled = false;
  Simulator sim(LoadSetup(options, ""));
  cv::HOGDescriptor hog;
  hog.setSVMDetector(cv::HOGDescriptor::getDefaultPeopleDetector());
  NullSink sink;
  int detections_total = 0, in_view = 0;
  for (double t : {0.0, 2.0, 4.0}) {
    sim.AdvanceTo(t, &sink);
    const Simulator::View view = sim.RenderView();
    for (int pixels : view.person_pixels) in_view += pixels > 800;
    cv::Mat image(view.height, view.width, CV_8UC3, const_cast<uint8_t*>(view.rgb.data())), bgr;
    cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
    std::vector<cv::Rect> detections;
    std::vector<double> weights;
    hog.detectMultiScale(bgr, detections, weights, 0.0, cv::Size(8, 8), cv::Size(16, 16), 1.05,
                         2.0);
    detections_total += static_cast<int>(detections.size());
  }
  std::printf("dark lab: %d people in view over 3 frames, %d HOG detections\n", in_view,
              detections_total);
  EXPECT_GE(in_view, 4);           // they are there (the depth camera sees them) ...
  EXPECT_EQ(detections_total, 0);  // ... but not in colour
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
