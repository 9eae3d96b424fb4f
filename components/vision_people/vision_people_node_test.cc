// sarmap-vision-people as a process over real LCM (inside a private network namespace):
// synthetic dark DEPTH + RGB in, confirmed depth-only people out; mismatched and empty frames
// are counted, not fatal; SIGINT stops it cleanly.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <optional>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/node.h"
#include "common/testing/isolated_network.h"
#include "sarmap/node_status_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "tests/node_watch.h"
#include "tests/process.h"
#include "vision_people/synthetic_scene.h"
#include "vision_people/vision_test_util.h"

namespace sarmap {
namespace vision_people {
namespace {

struct Sink {
  std::vector<people_detections_t> people;
  void OnPeople(const lcm::ReceiveBuffer*, const std::string&, const people_detections_t* m) {
    people.push_back(*m);
  }
};

using testing_util::KinectIntrinsics;

TEST(VisionPeopleNode, DarkRoomDepthOnlyPeopleAreConfirmedAndBadFramesCounted) {
  if (!sarmap::IsolatedNetwork())
    GTEST_SKIP() << "runs through tests/harness/sarmap-netns (ctest does)";
  const std::string src = SARMAP_SOURCE_DIR;
  const std::string log =
      ::testing::TempDir() + "/vision_people_node_" + std::to_string(getpid()) + ".log";
  testing::Process node(
      {"sarmap-vision-people", "--config", src + "/config/vision_people.yaml", "--set",
       "robot_config=" + src + "/config/robot.yaml", "--set", "confirmation.k=2", "--set",
       "confirmation.n=3", "--set", "max_rate_hz=0"},  // every frame of the 30 Hz stream
      log);
  lcm::LCM lcm(common::DefaultLcmUrl());
  ASSERT_TRUE(lcm.good());
  Sink sink;
  lcm.subscribe("PEOPLE_VISUAL", &Sink::OnPeople, &sink);
  testing::NodeStatusSink status("sarmap-vision-people");
  lcm.subscribe("NODE_STATUS", &testing::NodeStatusSink::OnStatus, &status);
  ASSERT_TRUE(testing::SpinUntil(
      lcm, [&] { return !status.message.empty(); }, 15))
      << node.Output();

  SyntheticScene scene;  // the robot.yaml mounting: 0.55 m, level
  scene.people.push_back({3.0, 0.4, 1.75, 0.3});
  scene.objects.push_back({SyntheticObject::kChair, 2.2, -0.6, 0.5, 0});
  std::vector<uint8_t> dark(640 * 480 * 3, 4);
  const int64_t t0 = 1700000000000000;
  auto send = [&](int i, int color_w, int color_h, bool empty_depth) {
    header_t h;
    h.utime = t0 + i * 33333;
    h.seq = i;
    h.frame = "camera";
    std::vector<uint8_t> rgb(color_w * color_h * 3, 4);
    image_t color = common::MakeColorImage(h, KinectIntrinsics(color_w, color_h), rgb.data(),
                                           color_w, color_h, 90);
    lcm.publish("RGB", &color);
    const std::vector<uint16_t> depth_mm = scene.RenderDepth(i);
    image_t depth =
        common::MakeDepthImage(h, KinectIntrinsics(640, 480), depth_mm.data(), 640, 480);
    if (empty_depth) {
      depth.width = depth.height = 0;
    }
    lcm.publish("DEPTH", &depth);
  };
  for (int i = 0; i < 4; ++i) {
    send(i, 640, 480, false);
    testing::SpinUntil(
        lcm, [&] { return static_cast<int>(sink.people.size()) > i; }, 10);
  }
  ASSERT_EQ(sink.people.size(), 4u) << node.Output();
  EXPECT_EQ(sink.people[0].num_detections, 0);  // 1 of 3: not yet confirmed
  int64_t track = -1;
  for (size_t i = 1; i < sink.people.size(); ++i) {
    ASSERT_EQ(sink.people[i].num_detections, 1) << "frame " << i;
    const person_detection_t& d = sink.people[i].detections[0];
    EXPECT_EQ(d.cue, static_cast<int8_t>(person_detection_t::CUE_SEEN_DEPTH));
    EXPECT_TRUE(d.has_range);
    EXPECT_NEAR(d.position_m[0], -0.4, 0.15);  // 0.4 m to the left: camera x = -0.4
    EXPECT_NEAR(d.position_m[2], 3.0, 0.25);
    EXPECT_GT(d.azimuth_rad, 0.0);  // left is positive
    EXPECT_NEAR(d.height_m, 1.75, 0.1);
    EXPECT_GT(d.position_covariance[8], 0.0);
    if (track < 0) track = d.track_id;
    EXPECT_EQ(d.track_id, track);
  }
  // Colour of the wrong size (counted by the frame assembler), then an empty depth image
  // (dropped as malformed by the node runtime's message checks, or counted by the
  // assembler): the node carries on.
  send(4, 320, 240, false);
  send(5, 640, 480, true);
  send(6, 640, 480, false);
  ASSERT_TRUE(testing::SpinUntil(
      lcm, [&] { return sink.people.size() >= 6; }, 10))
      << node.Output();
  EXPECT_EQ(sink.people.back().num_detections, 1);
  ASSERT_TRUE(testing::SpinUntil(
      lcm,
      [&] {
        const std::optional<int> warnings = status.InputWarnings();
        return warnings && *warnings + status.dropped >= 2;
      },
      5))
      << status.message << "; dropped " << status.dropped;
  ASSERT_TRUE(node.Running()) << node.Output();
  node.Signal(SIGINT);
  EXPECT_EQ(node.Wait(10), 0) << node.Output();
  EXPECT_NE(node.Output().find("color_size_mismatch"), std::string::npos) << node.Output();
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
