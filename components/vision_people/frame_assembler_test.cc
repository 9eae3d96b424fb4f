#include "vision_people/frame_assembler.h"

#include <gtest/gtest.h>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "vision_people/hog_classifier.h"
#include "vision_people/synthetic_scene.h"
#include "vision_people/vision_test_util.h"

namespace sarmap {
namespace vision_people {
namespace {

using testing_util::KinectIntrinsics;

sarmap::image_t Depth(int64_t utime, int w = 64, int h = 48, uint16_t value = 2000) {
  sarmap::header_t hd;
  hd.utime = utime;
  hd.seq = 0;
  hd.frame = "camera";
  std::vector<uint16_t> d(w * h, value);
  return common::MakeDepthImage(hd, KinectIntrinsics(w, h), d.data(), w, h);
}

sarmap::image_t Color(int64_t utime, int w = 64, int h = 48, uint8_t value = 120) {
  sarmap::header_t hd;
  hd.utime = utime;
  hd.seq = 0;
  hd.frame = "camera";
  std::vector<uint8_t> rgb(w * h * 3, value);
  return common::MakeColorImage(hd, KinectIntrinsics(w, h), rgb.data(), w, h, 90);
}

TEST(FrameAssembler, PairsByUtimeInEitherOrder) {
  FrameAssembler a(0.02, 0.1, false);
  std::vector<RgbdFrame> ready;
  a.AddDepth(Depth(1000000), &ready);
  EXPECT_TRUE(ready.empty());  // waits for its colour
  a.AddColor(Color(1005000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].has_color());
  EXPECT_EQ(ready[0].utime, 1000000);
  EXPECT_NEAR(ready[0].xyz[2], 2.0, 1e-6);
  ready.clear();
  a.AddColor(Color(1040000), &ready);
  a.AddDepth(Depth(1033000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].has_color());
  EXPECT_EQ(a.total_warnings(), 0);
}

TEST(FrameAssembler, MissingColourGoesDepthOnlyWithAWarning) {
  FrameAssembler a(0.02, 0.1, false);
  std::vector<RgbdFrame> ready;
  for (int i = 0; i < 6; ++i) a.AddDepth(Depth(1000000 + i * 33000), &ready);
  ASSERT_GE(ready.size(), 2u);
  EXPECT_FALSE(ready[0].has_color());
  EXPECT_GE(a.warnings().at("no_color"), 2);
  FrameAssembler strict(0.02, 0.1, true);
  ready.clear();
  for (int i = 0; i < 6; ++i) strict.AddDepth(Depth(1000000 + i * 33000), &ready);
  EXPECT_TRUE(ready.empty());
  EXPECT_GE(strict.warnings().at("no_color"), 2);
}

// A depth-only replay: every frame comes out once the bus goes quiet, the last one included.
TEST(FrameAssembler, FlushReleasesTheLastDepthOnlyFrame) {
  FrameAssembler a(0.02, 0.1, false);
  std::vector<RgbdFrame> ready;
  for (int i = 0; i < 5; ++i) a.AddDepth(Depth(1000000 + i * 150000), &ready);
  EXPECT_EQ(ready.size(), 4u);  // the last one waits for a colour image
  EXPECT_TRUE(a.has_pending());
  a.Flush(&ready);
  ASSERT_EQ(ready.size(), 5u);
  EXPECT_EQ(ready.back().utime, 1600000);
  EXPECT_FALSE(a.has_pending());
  a.Flush(&ready);  // nothing left: nothing happens
  EXPECT_EQ(ready.size(), 5u);
}

TEST(FrameAssembler, MismatchedEmptyAndCorruptFramesAreCountedNotFatal) {
  FrameAssembler a(0.02, 0.1, false);
  std::vector<RgbdFrame> ready;
  // Colour at a different resolution: counted, the frame goes on depth-only.
  a.AddColor(Color(2000000, 32, 24), &ready);
  a.AddDepth(Depth(2000000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_FALSE(ready[0].has_color());
  EXPECT_EQ(a.warnings().at("color_size_mismatch"), 1);
  ready.clear();
  // Empty depth image.
  sarmap::image_t empty = Depth(3000000);
  empty.width = 0;
  empty.height = 0;
  a.AddColor(Color(3000000), &ready);
  a.AddDepth(empty, &ready);
  EXPECT_TRUE(ready.empty());
  EXPECT_EQ(a.warnings().at("depth_empty"), 1);
  // Corrupt compressed payload.
  sarmap::image_t corrupt = Depth(3100000);
  corrupt.data.resize(corrupt.data.size() / 2);
  corrupt.size = static_cast<int32_t>(corrupt.data.size());
  a.AddColor(Color(3100000), &ready);
  a.AddDepth(corrupt, &ready);
  EXPECT_TRUE(ready.empty());
  EXPECT_EQ(a.warnings().at("depth_decode"), 1);
  // A colour image on the depth channel and vice versa.
  a.AddDepth(Color(3200000), &ready);
  a.AddColor(Depth(3200000), &ready);
  EXPECT_EQ(a.warnings().at("depth_format"), 1);
  EXPECT_EQ(a.warnings().at("color_format"), 1);
  // All-zero depth (no returns) decodes into an all-NaN frame; the detector reports it.
  a.AddColor(Color(3300000), &ready);
  a.AddDepth(Depth(3300000, 64, 48, 0), &ready);
  ASSERT_EQ(ready.size(), 1u);
  PeopleDetector detector(DetectorOptions(), SyntheticScene().ground(), nullptr);
  std::string error;
  EXPECT_TRUE(detector.Detect(ready[0], &error).people.empty());
  EXPECT_FALSE(error.empty());
  // Out of order depth.
  a.AddDepth(Depth(3400000), &ready);
  a.AddDepth(Depth(3350000), &ready);
  EXPECT_EQ(a.warnings().at("depth_out_of_order"), 1);
}

TEST(FrameAssembler, SyntheticFrameThroughMessagesStillFindsThePerson) {
  SyntheticScene scene;
  scene.people.push_back({3.0, 0.0, 1.75, 0.0});
  const auto depth_mm = scene.RenderDepth(7);
  sarmap::header_t hd;
  hd.utime = 5000000;
  hd.seq = 0;
  hd.frame = "camera";
  const auto depth =
      common::MakeDepthImage(hd, KinectIntrinsics(640, 480), depth_mm.data(), 640, 480);
  FrameAssembler a(0.02, 0.1, false);
  std::vector<RgbdFrame> ready;
  a.AddColor(Color(5000000, 640, 480, 3), &ready);  // dark
  a.AddDepth(depth, &ready);
  ASSERT_EQ(ready.size(), 1u);
  PeopleDetector detector(DetectorOptions(), scene.ground(), MakeOpenCvHogClassifier());
  const DetectionResult r = detector.Detect(ready[0]);
  EXPECT_EQ(r.stats.color_state, ColorState::kDark);
  ASSERT_EQ(r.people.size(), 1u);
  EXPECT_TRUE(r.people[0].depth_only);
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
