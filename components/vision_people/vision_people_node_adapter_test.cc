// VisionPeopleNode in-process over memq://: synthetic dark DEPTH + RGB in, people confirmed over
// k of n frames out, a frame stamped far ahead dropped, a 30 Hz camera thinned to max_rate_hz
// before decoding.
#include <gtest/gtest.h>

#include <vector>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "vision_people/synthetic_scene.h"
#include "vision_people/vision_people_node.h"
#include "vision_people/vision_test_util.h"

namespace sarmap {
namespace vision_people {
namespace {

using testing_util::KinectIntrinsics;

struct Bus {
  common::Node node{"vision_people_node_test", "memq://"};
  std::vector<people_detections_t> people;
  common::Node::Publisher<image_t> depth_pub = node.Advertise<image_t>("DEPTH");
  common::Node::Publisher<image_t> rgb_pub = node.Advertise<image_t>("RGB");
  SyntheticScene scene;  // the robot.yaml mounting: 0.55 m, level
  Bus() {
    node.Subscribe<people_detections_t>(
        "PEOPLE_VISUAL",
        [this](const people_detections_t& m, const auto&) { people.push_back(m); });
    scene.people.push_back({3.0, 0.4, 1.75, 0.3});
    scene.objects.push_back({SyntheticObject::kChair, 2.2, -0.6, 0.5, 0});
  }
  // A dark colour frame and the scene's depth at `utime`; with `corrupt_depth` the depth's
  // compressed bytes are cut short, so decoding it fails.
  void Send(int i, int64_t utime, bool corrupt_depth = false) {
    header_t h;
    h.utime = utime;
    h.seq = i;
    h.frame = "camera";
    std::vector<uint8_t> rgb(640 * 480 * 3, 4);
    image_t color = common::MakeColorImage(h, KinectIntrinsics(640, 480), rgb.data(), 640, 480, 90);
    rgb_pub.Publish(&color);
    const std::vector<uint16_t> depth_mm = scene.RenderDepth(i);
    image_t depth =
        common::MakeDepthImage(h, KinectIntrinsics(640, 480), depth_mm.data(), 640, 480);
    if (corrupt_depth) {
      depth.data.resize(depth.data.size() / 2);
      depth.size = static_cast<int32_t>(depth.data.size());
    }
    depth_pub.Publish(&depth);
    for (int k = 0; k < 4; ++k) node.SpinOnce(0.001);
  }
};

VisionPeopleOptions Options() {
  VisionPeopleOptions options;
  options.confirmation.k = 2;
  options.confirmation.n = 3;
  return options;
}

TEST(VisionPeopleNodeTest, DarkDepthOnlyPeopleAreConfirmedOverKOfNFrames) {
  Bus bus;
  VisionPeopleNode adapter(Options(), &bus.node);
  const int64_t t0 = 1700000000000000;
  for (int i = 0; i < 4; ++i) bus.Send(i, t0 + i * 33333);
  ASSERT_EQ(bus.people.size(), 4u);
  EXPECT_EQ(adapter.frames(), 4);
  EXPECT_EQ(bus.people[0].num_detections, 0);  // 1 of 3: not yet confirmed
  for (size_t i = 1; i < bus.people.size(); ++i) {
    ASSERT_EQ(bus.people[i].num_detections, 1) << "frame " << i;
    const person_detection_t& d = bus.people[i].detections[0];
    EXPECT_EQ(d.cue, static_cast<int8_t>(person_detection_t::CUE_SEEN_DEPTH));
    EXPECT_NEAR(d.position_m[0], -0.4, 0.15);  // 0.4 m to the left: camera x = -0.4
    EXPECT_NEAR(d.position_m[2], 3.0, 0.25);
    EXPECT_EQ(bus.people[i].header.utime, t0 + static_cast<int64_t>(i) * 33333);
  }
}

TEST(VisionPeopleNodeTest, AFrameStampedFarAheadIsDroppedAndLaterFramesGoOn) {
  Bus bus;
  VisionPeopleNode adapter(Options(), &bus.node);
  const int64_t t0 = 1700000000000000;
  bus.Send(0, t0);
  bus.Send(1, t0 + 365LL * 86400 * 1'000'000);  // both images a year ahead: both dropped
  for (int i = 2; i < 5; ++i) bus.Send(i, t0 + i * 33333);
  EXPECT_EQ(bus.node.stats().at("DEPTH").dropped_malformed, 1);
  EXPECT_EQ(bus.node.stats().at("RGB").dropped_malformed, 1);
  ASSERT_EQ(bus.people.size(), 4u);
  EXPECT_EQ(bus.people.back().num_detections, 1);
  EXPECT_EQ(bus.people.back().header.utime, t0 + 4 * 33333);
}

// A 30 Hz camera with max_rate_hz 15: every second frame is detected in and published, the
// others are skipped and counted, and passed over before they are decoded: undecodable depth
// at a stamp that is thinned out raises no decoding warning, at a stamp that is taken it does.
TEST(VisionPeopleNodeTest, MaxRateKeepsEverySecondFrameOfAThirtyHertzCamera) {
  Bus bus;
  VisionPeopleOptions options = Options();
  options.max_rate_hz = 15;
  VisionPeopleNode adapter(options, &bus.node);
  const int64_t t0 = 1700000000000000;
  for (int i = 0; i < 6; ++i) bus.Send(i, t0 + i * 33333, /*corrupt_depth=*/i == 3);
  EXPECT_EQ(adapter.frames(), 3);
  EXPECT_EQ(adapter.skipped_frames(), 3);
  EXPECT_EQ(adapter.pairing_warnings().count("depth_decode"), 0u);
  ASSERT_EQ(bus.people.size(), 3u);
  for (size_t i = 0; i < bus.people.size(); ++i)
    EXPECT_EQ(bus.people[i].header.utime, t0 + static_cast<int64_t>(2 * i) * 33333);
  EXPECT_EQ(bus.people.back().num_detections, 1);  // confirmed over 2 of the 3 frames detected in
  bus.Send(6, t0 + 6 * 33333, /*corrupt_depth=*/true);
  ASSERT_EQ(adapter.pairing_warnings().count("depth_decode"), 1u);
  EXPECT_EQ(adapter.pairing_warnings().at("depth_decode"), 1);
  EXPECT_EQ(adapter.frames(), 3);
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
