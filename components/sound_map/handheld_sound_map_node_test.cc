// sarmap-handheld-sound-map as a process over real LCM (run in a private network namespace by
// CTest): a hand-held rig's RIG_POSE and its Kinect array's KIND_ANGLE_1D DOAs in, SOUND_MAP out.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "sarmap/doa_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/sound_map_t.hpp"
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
  if (!getenv("SARMAP_NETNS"))
    GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
  const Walk w = RunWalk(false);
  EXPECT_EQ(w.exit_code, 0);
  const Sink& sink = w.sink;
  ASSERT_GT(sink.maps, 0) << w.output;
  ASSERT_EQ(sink.map.num_sources, 1) << w.output;
  const Eigen::Vector3d source(2.0, 2.5, 1.3);
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
  if (!getenv("SARMAP_NETNS"))
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
  // The rig walks 3 m along x and 2 m along y, raised and lowered by 0.3 m as a hand does; a
  // source at (2, 2.5, 1.3). The Kinect's bar (the array's x axis) lies along the rig's y, 3 cm
  // below the camera (config/handheld_sound_map.yaml).
  const Eigen::Vector3d source(2.0, 2.5, 1.3);
  Eigen::Isometry3d rig_from_mic = Eigen::Isometry3d::Identity();
  rig_from_mic.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  rig_from_mic.translation() = Eigen::Vector3d(0, 0, -0.03);
  const int steps = 125;
  for (int k = 0; k < steps; ++k) {
    const int64_t t = 1000000 + k * 100000;
    const double s = 0.04 * k;  // path length
    Eigen::Isometry3d odom_from_rig = Eigen::Isometry3d::Identity();
    const double yaw = s < 3.0 ? 0.0 : M_PI / 2;
    odom_from_rig.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    odom_from_rig.translation() =
        s < 3.0 ? Eigen::Vector3d(s, 0, 0) : Eigen::Vector3d(3.0, s - 3.0, 0);
    odom_from_rig.translation().z() = 1.2 + 0.3 * std::sin(2 * M_PI * s / 1.5);
    sarmap::pose_t pose{};
    pose.header.utime = t;
    pose.header.frame = "odom";
    pose.child_frame = "rig";
    const Eigen::Quaterniond q(odom_from_rig.linear());
    pose.orientation[0] = q.w();
    pose.orientation[1] = q.x();
    pose.orientation[2] = q.y();
    pose.orientation[3] = q.z();
    for (int i = 0; i < 3; ++i) pose.position_m[i] = odom_from_rig.translation()[i];
    pose.node_id = -1;
    if (k == 10) {  // a broken pose: counted and dropped, nothing else
      sarmap::pose_t bad = pose;
      bad.orientation[0] = 3;
      lcm.publish("RIG_POSE", &bad);
    }
    if (future_poses && (k == 20 || k == 21)) {
      constexpr int64_t kYearUs = 365LL * 24 * 3600 * 1000000;
      sarmap::pose_t future = pose;
      future.header.utime = t + kYearUs;
      lcm.publish("RIG_POSE", &future);
    }
    w.last_utime = t + 1;
    lcm.publish("RIG_POSE", &pose);
    const Eigen::Vector3d p_mic = (odom_from_rig * rig_from_mic).inverse() * source;
    sarmap::doa_t doa{};
    doa.header.utime = t + 1;
    doa.header.frame = "mic_array";
    doa.device_id = "kinect";
    sarmap::doa_source_t d{};
    d.track_id = 3;
    d.kind = sarmap::doa_source_t::KIND_ANGLE_1D;
    d.method = sarmap::doa_source_t::METHOD_SRP_PHAT;
    d.confidence = 1;
    d.azimuth_rad =
        std::acos(p_mic.x() / p_mic.norm()) + 1.5 * M_PI / 180 * std::sin(7.3 * k);  // +-1.5 deg
    d.covariance[0] = std::pow(3 * M_PI / 180, 2);
    d.covariance[3] = 1;
    doa.sources.push_back(d);
    sarmap::doa_source_t azimuth = d;  // another kind of DOA: ignored, counted
    azimuth.kind = sarmap::doa_source_t::KIND_AZIMUTH;
    azimuth.track_id = 4;
    doa.sources.push_back(azimuth);
    doa.num_sources = 2;
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
