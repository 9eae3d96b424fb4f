// sarmap-sound-map as a process over real LCM (run in a private network namespace by
// CTest): POSE + DOA (DOA_MAP) + SLAM_ANCHORS + PEOPLE_AUDIO in, SLAM_ANCHOR_REQUEST and
// SOUND_MAP out, with the configured reorder delay.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "common/testing/isolated_network.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "tests/process.h"

namespace {

struct Sink {
  sarmap::sound_map_t map;
  sarmap::slam_anchor_request_t request;
  int maps = 0, requests = 0;
  int64_t newest_map_utime = 0;
  void OnMap(const lcm::ReceiveBuffer*, const std::string&, const sarmap::sound_map_t* m) {
    map = *m;
    ++maps;
    newest_map_utime = std::max(newest_map_utime, m->header.utime);
  }
  void OnRequest(const lcm::ReceiveBuffer*, const std::string&,
                 const sarmap::slam_anchor_request_t* m) {
    request = *m;
    ++requests;
  }
};

// One step k of a robot driving along +x at 0.5 m/s: POSE, a DOA towards the source at
// (sx, sy) on DOA_MAP and SLAM_ANCHORS, 0.1 s apart in message time.
void PublishStep(lcm::LCM& lcm, int k, double sx, double sy) {
  const int64_t t = 1000000 + k * 100000;
  sarmap::pose_t pose{};
  pose.header.utime = t;
  pose.header.frame = "map";
  pose.child_frame = "base";
  pose.position_m[0] = 0.05 * k;
  pose.orientation[0] = 1;
  for (int i : {0, 7, 35}) pose.covariance[i] = 1e-4;
  pose.node_id = k / 10;
  lcm.publish("POSE", &pose);
  sarmap::doa_t doa{};
  doa.header.utime = t + 1;
  doa.header.frame = "mic_array";
  doa.device_id = "kinect";
  sarmap::doa_source_t s{};
  s.track_id = 5;
  s.kind = sarmap::doa_source_t::KIND_AZIMUTH;
  s.method = sarmap::doa_source_t::METHOD_SRP_PHAT;
  s.confidence = 1;
  s.sound_class = sarmap::doa_source_t::SOUND_CLASS_VOICE;
  s.class_confidence = 0.8f;
  s.azimuth_rad = std::atan2(sy, sx - (0.05 * k + 0.10));
  s.covariance[0] = std::pow(3 * M_PI / 180, 2);
  s.covariance[3] = 1;
  doa.sources.push_back(s);
  doa.num_sources = 1;
  lcm.publish("DOA_MAP", &doa);  // config/sound_map.yaml: the localiser's map stream
  sarmap::slam_anchors_t a{};
  a.header.utime = t + 2;
  a.header.frame = "map";
  a.optimisation_id = k;
  a.current = {k / 10, t, 0.05 * k, 0, 0};
  a.num_anchors = 1;
  a.anchors.push_back({0, 1000000, 0, 0, 0});
  a.covariance_dim = 6;
  a.covariance.assign(6, std::vector<double>(6, 0.0));
  for (int i = 0; i < 6; ++i) a.covariance[i][i] = 1e-4;
  lcm.publish("SLAM_ANCHORS", &a);
}

constexpr char kUrl[] = "udpm://239.255.76.67:7667?ttl=0";

// sarmap-sound-map on kUrl with the shipped config and robot.
std::vector<std::string> NodeCommand() {
  const std::string config_dir = std::string(SARMAP_SOURCE_DIR) + "/config";
  return {"sarmap-sound-map",
          "--lcm-url",
          kUrl,
          "--config",
          config_dir + "/sound_map.yaml",
          "--set",
          "robot_config=" + config_dir + "/robot.yaml"};
}

// Gives the node time to apply its last reorder_delay_s of inputs, stops it (a clean exit
// expected) and hears the final map it sends.
void StopAndHearTheFinalMap(lcm::LCM& lcm, sarmap::testing::Process& node) {
  for (int i = 0; i < 20; ++i) lcm.handleTimeout(50);
  node.Signal(SIGTERM);
  EXPECT_EQ(node.Wait(5), 0);
  for (int i = 0; i < 10; ++i) lcm.handleTimeout(50);
}

// Each test: a bus to the node (in a private network namespace) and the maps it sends.
class SoundMapNode : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!sarmap::IsolatedNetwork())
      GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
    ASSERT_TRUE(lcm.good());
    lcm.subscribe("SOUND_MAP", &Sink::OnMap, &sink);
  }
  lcm::LCM lcm{kUrl};
  Sink sink;
};

TEST_F(SoundMapNode, MapsASourceFromPoseDoaAndAnchors) {
  const std::string log =
      ::testing::TempDir() + "/sound-map-node-" + std::to_string(getpid()) + ".log";
  sarmap::testing::Process node(NodeCommand(), log);
  lcm.subscribe("SLAM_ANCHOR_REQUEST", &Sink::OnRequest, &sink);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // The array sits 0.10 m ahead of the base (config/robot.yaml); a source at (3, 2).
  const double sx = 3.0, sy = 2.0;
  for (int k = 0; k < 40; ++k) {
    PublishStep(lcm, k, sx, sy);
    if (k == 39) {
      // A call heard at message time 3.0 s (k = 20), published 1.9 s later, as sarmap-speech does
      // (decoded when the utterance ends, then held for the other beams' hits).
      sarmap::people_detections_t heard{};
      heard.header.utime = 1000000 + 20 * 100000;
      heard.header.frame = "mic_array";
      sarmap::person_detection_t d{};
      d.cue = sarmap::person_detection_t::CUE_HEARD;
      d.azimuth_rad = std::atan2(sy, sx - (0.05 * 20 + 0.10));
      d.direction_covariance[0] = std::pow(3 * M_PI / 180, 2);
      d.direction_covariance[3] = 1;
      d.confidence = 0.9f;
      d.keyword = "help";
      heard.detections.push_back(d);
      heard.num_detections = 1;
      lcm.publish("PEOPLE_AUDIO", &heard);
    }
    lcm.handleTimeout(10);
  }
  // The last reorder_delay_s of inputs is applied when the node stops, and the final map sent.
  StopAndHearTheFinalMap(lcm, node);
  ASSERT_GT(sink.requests, 0) << node.Output();
  EXPECT_EQ(sink.request.num_node_ids, 1);
  EXPECT_EQ(sink.request.node_ids.at(0), 0);
  ASSERT_EQ(sink.map.num_sources, 1) << node.Output();
  const auto& src = sink.map.sources[0];
  printf("mapped source at (%.3f, %.3f), %d observations\n", src.position_m[0], src.position_m[1],
         src.num_observations);
  EXPECT_NEAR(src.position_m[0], sx, 0.3);
  EXPECT_NEAR(src.position_m[1], sy, 0.3);
  EXPECT_GE(src.num_observations, 30);
  // The late call still reached the map (with a 0.3 s delay it was dropped as late).
  EXPECT_TRUE(src.has_position) << node.Output();
  EXPECT_EQ(src.sound_class, +sarmap::doa_source_t::SOUND_CLASS_VOICE);
  EXPECT_EQ(src.priority, +sarmap::sound_source_t::PRIORITY_CALL);
  EXPECT_TRUE(src.is_person) << node.Output();
}

// Two POSEs stamped a year ahead (a skewed clock, a forged message) are dropped and counted:
// the inputs after them are still used and SOUND_MAP keeps its stamps.
TEST_F(SoundMapNode, FarFuturePosesAreDroppedAndTheMapGoesOn) {
  const std::string log =
      ::testing::TempDir() + "/sound-map-future-" + std::to_string(getpid()) + ".log";
  sarmap::testing::Process node(NodeCommand(), log);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const double sx = 3.0, sy = 2.0;
  constexpr int64_t kYearUs = 365LL * 24 * 3600 * 1000000;
  for (int k = 0; k < 60; ++k) {
    if (k == 10 || k == 11) {
      sarmap::pose_t future{};
      future.header.utime = 1000000 + k * 100000 + kYearUs;
      future.header.frame = "map";
      future.child_frame = "base";
      future.position_m[0] = 0.05 * k;
      future.orientation[0] = 1;
      for (int i : {0, 7, 35}) future.covariance[i] = 1e-4;
      lcm.publish("POSE", &future);
    }
    PublishStep(lcm, k, sx, sy);
    lcm.handleTimeout(10);
  }
  StopAndHearTheFinalMap(lcm, node);
  ASSERT_EQ(sink.map.num_sources, 1) << node.Output();
  // DOAs after the future poses were used (60 published, the last reorder delay's flushed at exit).
  EXPECT_GE(sink.map.sources[0].num_observations, 45) << node.Output();
  EXPECT_LT(sink.newest_map_utime, 1000000 + 60 * 100000) << node.Output();
}

}  // namespace
