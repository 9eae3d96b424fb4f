// sarmap-handheld-sound-map as a process over real LCM (run in a private network namespace by
// CTest): a hand-held rig's RIG_POSE and its Kinect array's KIND_ANGLE_1D DOAs in, SOUND_MAP out.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "common/testing/isolated_network.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "handheld_sound_map/handheld_walk_test_util.h"
#include "tests/process.h"

namespace {

struct Sink {
  sarmap::sound_map_t map;
  int maps = 0;
  void OnMap(const lcm::ReceiveBuffer*, const std::string&, const sarmap::sound_map_t* m) {
    map = *m;
    ++maps;
  }
};

// The walk below; future_poses: two RIG_POSEs stamped a year ahead in it (a skewed or forged
// clock), which the node's stamp gate drops.
struct Walk {
  Sink sink;
  int64_t last_utime = 0;
  std::string output;
  int exit_code = -1;
};
Walk RunWalk(bool future_poses);

TEST(HandheldSoundMapNode, MapsASourceFromRigPosesAndLinearArrayAngles) {
  if (!sarmap::IsolatedNetwork())
    GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
  const Walk w = RunWalk(false);
  EXPECT_EQ(w.exit_code, 0);
  const Sink& sink = w.sink;
  ASSERT_GT(sink.maps, 0) << w.output;
  ASSERT_EQ(sink.map.num_sources, 1) << w.output;
  const Eigen::Vector3d source = sarmap::sound_map::testing_util::WalkSource();
  const auto& src = sink.map.sources[0];
  const Eigen::Vector3d p(src.position_m[0], src.position_m[1], src.position_m[2]);
  printf("mapped source at (%.3f, %.3f, %.3f), %d observations, state %d, error %.3f m\n", p.x(),
         p.y(), p.z(), src.num_observations, src.state, (p - source).norm());
  EXPECT_EQ(src.state, +sarmap::sound_source_t::STATE_CONVERGED) << w.output;
  EXPECT_LT((p - source).norm(), 0.3);
  EXPECT_GE(src.num_observations, 100);
  EXPECT_NE(w.output.find("not KIND_ANGLE_1D"), std::string::npos) << w.output;
  EXPECT_NE(w.output.find("not a unit quaternion"), std::string::npos) << w.output;
}

// Two RIG_POSEs a year ahead: without the stamp gate they became the node's clock, every later
// input was late and SOUND_MAP went out a year ahead.
TEST(HandheldSoundMapNode, FarFuturePosesAreDroppedAndTheMapGoesOn) {
  if (!sarmap::IsolatedNetwork())
    GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
  const Walk w = RunWalk(true);
  EXPECT_EQ(w.exit_code, 0);
  ASSERT_EQ(w.sink.map.num_sources, 1) << w.output;
  EXPECT_GE(w.sink.map.sources[0].num_observations, 100) << w.output;
  EXPECT_LE(w.sink.map.header.utime, w.last_utime) << w.output;
}

Walk RunWalk(bool future_poses) {
  Walk w;
  Sink& sink = w.sink;
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  const std::string log =
      ::testing::TempDir() + "/handheld-sound-map-node-" + std::to_string(getpid()) + ".log";
  sarmap::testing::Process node(
      {"sarmap-handheld-sound-map", "--lcm-url", url, "--config",
       std::string(SARMAP_SOURCE_DIR) + "/config/handheld_sound_map.yaml"},
      log);
  lcm::LCM lcm(url);
  if (!lcm.good()) return w;
  lcm.subscribe("SOUND_MAP", &Sink::OnMap, &sink);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  for (int k = 0; k < sarmap::sound_map::testing_util::kWalkSteps; ++k) {
    const sarmap::pose_t pose = sarmap::sound_map::testing_util::WalkPose(k);
    if (k == 10) {  // a broken pose: counted and dropped, nothing else
      sarmap::pose_t bad = pose;
      bad.orientation[0] = 3;
      lcm.publish("RIG_POSE", &bad);
    }
    if (future_poses && (k == 20 || k == 21)) {
      constexpr int64_t kYearUs = 365LL * 24 * 3600 * 1000000;
      sarmap::pose_t future = pose;
      future.header.utime = pose.header.utime + kYearUs;
      lcm.publish("RIG_POSE", &future);
    }
    w.last_utime = pose.header.utime + 1;
    lcm.publish("RIG_POSE", &pose);
    const sarmap::doa_t doa = sarmap::sound_map::testing_util::WalkDoa(k);
    lcm.publish("DOA_MAP", &doa);
    lcm.handleTimeout(10);
  }
  for (int i = 0; i < 20; ++i) lcm.handleTimeout(50);
  node.Signal(SIGTERM);
  w.exit_code = node.Wait(10);
  for (int i = 0; i < 10; ++i) lcm.handleTimeout(50);
  w.output = node.Output();
  return w;
}

}  // namespace
