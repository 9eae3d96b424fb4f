// Multi-process test (private network namespace, real LCM): sarmap-slam fed with the start of
// the Intel log is killed (SIGKILL) half-way and restarted from its saved state; it must
// resume mapping (continuing the graph, poses continuous), reject garbage with counted
// warnings, answer anchor requests with a joint covariance, and report SCAN -> POSE latency.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <thread>

#include "common/node.h"
#include "common/time.h"
#include "common/transform.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/node_status_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "slam/carmen.h"
#include "slam/carmen_messages.h"
#include "tests/process.h"

namespace sarmap {
namespace {

const std::string kIntel = std::string(SARMAP_DATA_DIR) + "/slam/intel/intel.log";

struct Event {
  double t = 0;
  bool is_scan = false;
  laser_scan_t scan;
  odometry_t odom;
};

std::vector<Event> LoadIntelPrefix(int max_scans) {
  std::vector<Event> events;
  slam::CarmenReader reader;
  int scans = 0;
  reader.on_odometry = [&](const slam::CarmenOdometry& o) {
    if (scans >= max_scans) return;
    Event e;
    e.t = o.time_s;
    e.is_scan = false;
    e.odom = slam::ToOdometryMessage(o);
    events.push_back(std::move(e));
  };
  reader.on_laser = [&](const slam::CarmenLaser& l) {
    if (scans++ >= max_scans) return;
    Event e;
    e.t = l.time_s;
    e.is_scan = true;
    e.scan = slam::ToScanMessage(l);
    events.push_back(std::move(e));
  };
  slam::ReadCarmenFile(kIntel, &reader);
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t < b.t; });
  return events;
}

class Listener {
 public:
  explicit Listener(lcm::LCM* lcm) {
    lcm->subscribe("POSE", &Listener::OnPose, this);
    lcm->subscribe("SLAM_ANCHORS", &Listener::OnAnchors, this);
  }
  void OnPose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* m) {
    std::lock_guard<std::mutex> lock(mu);
    poses[m->header.utime] = *m;
    receive_s[m->header.utime] = common::SteadySeconds();
  }
  void OnAnchors(const lcm::ReceiveBuffer*, const std::string&, const slam_anchors_t* m) {
    std::lock_guard<std::mutex> lock(mu);
    anchors.push_back(*m);
  }
  std::mutex mu;
  std::map<int64_t, pose_t> poses;
  std::map<int64_t, double> receive_s;
  std::vector<slam_anchors_t> anchors;
};

// Handles LCM for `seconds` of wall time.
void HandleFor(lcm::LCM* lcm, double seconds) {
  const double until = common::SteadySeconds() + seconds;
  while (common::SteadySeconds() < until) lcm->handleTimeout(10);
}

// Stops the node with SIGTERM: it must exit cleanly.
void StopCleanly(testing::Process& node) {
  node.Signal(SIGTERM);
  EXPECT_EQ(node.Wait(20), 0) << node.Output();
}

// Publishes events [begin, end) at `rate_hz` scans per second, handling LCM meanwhile.
void Publish(lcm::LCM* lcm, const std::vector<Event>& ev, size_t begin, size_t end, double rate_hz,
             std::map<int64_t, double>* sent_s) {
  for (size_t i = begin; i < end; ++i) {
    if (ev[i].is_scan) {
      laser_scan_t scan = ev[i].scan;
      (*sent_s)[scan.header.utime] = common::SteadySeconds();
      lcm->publish("SCAN", &scan);
      const double until = common::SteadySeconds() + 1.0 / rate_hz;
      while (common::SteadySeconds() < until) lcm->handleTimeout(2);
    } else {
      odometry_t odom = ev[i].odom;
      lcm->publish("ODOM", &odom);
    }
  }
}

// Each test: a bus to the node, what arrives on it, and when each scan was sent.
class SlamNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::ifstream(kIntel)) GTEST_SKIP() << "shared data missing: " << kIntel;
    ASSERT_TRUE(lcm.good());
  }
  lcm::LCM lcm{common::kDefaultLcmUrl};
  Listener listener{&lcm};
  std::map<int64_t, double> sent_s;
};

TEST_F(SlamNodeTest, KilledAndRestartedFromSavedStateResumesMapping) {
  const std::vector<Event> events = LoadIntelPrefix(500);
  size_t half = 0;
  for (int scans = 0; half < events.size() && scans < 250; ++half) scans += events[half].is_scan;
  const std::string state = ::testing::TempDir() + "/slam_node_test.pg";
  std::remove(state.c_str());
  const std::vector<std::string> args = {"sarmap-slam",
                                         "--config",
                                         "",
                                         "--set",
                                         "state_file=" + state,
                                         "--set",
                                         "resume=true",
                                         "--set",
                                         "state_save_period_s=3",
                                         "--set",
                                         "slam.graph.optimise_every_n_nodes=30"};

  auto node = std::make_unique<testing::Process>(args, ::testing::TempDir() + "/slam_node_1.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // Garbage: two scans with NaN ranges (the second with 90 beams: a beam count of its own is
  // not garbage, the NaN is).
  Publish(&lcm, events, 0, 40, 40, &sent_s);
  // (Stamped just before the next scan to come, so the time-ordered queue takes them.)
  laser_scan_t bad = events[0].scan;
  for (size_t i = 40; i < events.size(); ++i) {
    if (events[i].is_scan) {
      bad = events[i].scan;
      break;
    }
  }
  bad.header.utime -= 1000;
  bad.ranges_m[5] = std::nanf("");
  lcm.publish("SCAN", &bad);
  bad.header.utime += 100;
  bad.ranges_m.resize(90);
  bad.num_ranges = 90;
  lcm.publish("SCAN", &bad);
  Publish(&lcm, events, 40, half, 40, &sent_s);
  // Ask for anchors, let one more optimisation happen, then crash the node.
  slam_anchor_request_t request{};
  request.client_id = "test";
  request.node_ids = {2, 5};
  request.num_node_ids = 2;
  lcm.publish("SLAM_ANCHOR_REQUEST", &request);
  HandleFor(&lcm, 2.0);
  node->Signal(SIGKILL);
  node->Wait(5);
  const std::string log1 = node->Output();
  EXPECT_NE(log1.find("scan rejected"), std::string::npos) << log1;
  ASSERT_TRUE(std::ifstream(state).good()) << "no state saved before the crash";
  int64_t last_node_before = -1;
  common::Rigid2d last_pose_before;
  {
    std::lock_guard<std::mutex> lock(listener.mu);
    ASSERT_GT(listener.poses.size(), 100u);
    last_node_before = listener.poses.rbegin()->second.node_id;
    const auto& p = listener.poses.rbegin()->second;
    last_pose_before = common::Rigid2d(p.position_m[0], p.position_m[1],
                                     2 * std::atan2(p.orientation[3], p.orientation[0]));
  }

  // Restart: the node loads the state and continues.
  node = std::make_unique<testing::Process>(args, ::testing::TempDir() + "/slam_node_2.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const size_t poses_before = listener.poses.size();
  lcm.publish("SLAM_ANCHOR_REQUEST", &request);  // clients repeat their request to a new node
  Publish(&lcm, events, half, events.size(), 40, &sent_s);
  HandleFor(&lcm, 2.0);
  StopCleanly(*node);
  const std::string log2 = node->Output();
  EXPECT_NE(log2.find("resumed mapping"), std::string::npos) << log2;

  std::lock_guard<std::mutex> lock(listener.mu);
  ASSERT_GT(listener.poses.size(), poses_before + 100);
  // The graph continues: node ids after the restart go beyond the ones before the crash.
  EXPECT_GT(listener.poses.rbegin()->second.node_id, last_node_before);
  // The first pose after the restart continues from the last one before the crash (the robot
  // moves ~0.3 m/s; the scans between crash and restart are lost).
  const pose_t& first_after = listener.poses.upper_bound(
      std::prev(listener.poses.end(), listener.poses.size() - poses_before)->first - 1)->second;
  const double jump = std::hypot(first_after.position_m[0] - last_pose_before.translation().x(),
                                 first_after.position_m[1] - last_pose_before.translation().y());
  std::printf("first pose after restart is %.3f m from the last before the crash\n", jump);
  EXPECT_LT(jump, 1.0);
  // Covariance on POSE, anchors with the joint covariance.
  EXPECT_GT(listener.poses.rbegin()->second.covariance[0], 0.0);
  bool saw_anchors = false;
  for (const auto& a : listener.anchors) {
    if (a.num_anchors != 2) continue;
    saw_anchors = true;
    ASSERT_EQ(a.covariance_dim, 9);
    for (int i = 0; i < 9; ++i) EXPECT_GE(a.covariance[i][i], 0.0);
    EXPECT_NEAR(a.covariance[1][4], a.covariance[4][1], 1e-12);  // symmetric
  }
  EXPECT_TRUE(saw_anchors);
  // SCAN -> POSE latency (wall clock, this machine, through real LCM).
  std::vector<double> latency;
  for (const auto& [utime, t] : listener.receive_s) {
    auto it = sent_s.find(utime);
    if (it != sent_s.end()) latency.push_back(t - it->second);
  }
  std::sort(latency.begin(), latency.end());
  ASSERT_FALSE(latency.empty());
  std::printf("SCAN->POSE latency over %zu scans: median %.1f ms, p99 %.1f ms (queue delay 100 ms "
              "of message time included)\n",
              latency.size(), 1e3 * latency[latency.size() / 2],
              1e3 * latency[std::min(latency.size() - 1, size_t(0.99 * latency.size()))]);
}

// Index of the n-th scan in `events` (events.size() when there are fewer).
size_t NthScan(const std::vector<Event>& events, int n) {
  size_t i = 0;
  for (int scans = 0; i < events.size(); ++i) {
    if (events[i].is_scan && scans++ == n) break;
  }
  return i;
}

// One SCAN stamped a year ahead, then a pause long enough for the queue to flush: the scan is
// dropped and counted, POSE goes on with the scans after it and is never stamped in the future.
TEST_F(SlamNodeTest, AFarFutureScanIsDroppedAndPoseGoesOn) {
  const std::vector<Event> events = LoadIntelPrefix(160);
  testing::Process node({"sarmap-slam", "--config", ""},
                        ::testing::TempDir() + "/slam_node_future.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const size_t split = NthScan(events, 60);
  Publish(&lcm, events, 0, split, 40, &sent_s);
  laser_scan_t future = events[split].scan;
  future.header.utime += 365LL * 24 * 3600 * 1000000;
  lcm.publish("SCAN", &future);
  HandleFor(&lcm, 0.5);
  const int64_t split_utime = events[split].scan.header.utime;
  Publish(&lcm, events, split, events.size(), 40, &sent_s);
  HandleFor(&lcm, 2.0);
  StopCleanly(node);

  std::lock_guard<std::mutex> lock(listener.mu);
  ASSERT_FALSE(listener.poses.empty()) << node.Output();
  const int64_t last_input_utime =
      events.back().is_scan ? events.back().scan.header.utime : events.back().odom.header.utime;
  EXPECT_LE(listener.poses.rbegin()->first, last_input_utime) << "POSE stamped in the future";
  // The 100 scans after the future one are mapped (a few may be skipped by the matcher).
  const auto after = std::distance(listener.poses.lower_bound(split_utime), listener.poses.end());
  EXPECT_GE(after, 80) << node.Output();
}

// Anchor requests from 300 new client ids, each naming every node: a few are answered, the rest
// refused and counted, and POSE goes on.
TEST_F(SlamNodeTest, AnchorRequestFloodIsRateLimited) {
  const std::vector<Event> events = LoadIntelPrefix(160);
  int64_t refused = 0;
  struct StatusSink {
    int64_t* refused;
    void OnStatus(const lcm::ReceiveBuffer*, const std::string&, const node_status_t* m) {
      if (m->node_name != "sarmap-slam") return;
      for (const auto& c : m->channels) {
        if (c.channel == "SLAM_ANCHOR_REQUEST") *refused = std::max(*refused, c.dropped_malformed);
      }
    }
  } status{&refused};
  lcm.subscribe("NODE_STATUS", &StatusSink::OnStatus, &status);
  testing::Process node({"sarmap-slam", "--config", ""},
                        ::testing::TempDir() + "/slam_node_flood.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const size_t split = NthScan(events, 80);
  Publish(&lcm, events, 0, split, 40, &sent_s);
  {
    std::lock_guard<std::mutex> lock(listener.mu);
    listener.anchors.clear();
  }
  constexpr int kClients = 300;
  for (int i = 0; i < kClients; ++i) {
    slam_anchor_request_t request{};
    request.client_id = "flood-" + std::to_string(i);
    for (int id = 0; id < 80; ++id) request.node_ids.push_back(id);
    request.num_node_ids = static_cast<int32_t>(request.node_ids.size());
    lcm.publish("SLAM_ANCHOR_REQUEST", &request);
    lcm.handleTimeout(1);
  }
  const int64_t split_utime = events[split].scan.header.utime;
  Publish(&lcm, events, split, events.size(), 40, &sent_s);
  HandleFor(&lcm, 2.0);
  StopCleanly(node);

  std::lock_guard<std::mutex> lock(listener.mu);
  std::printf("%d anchor requests from new clients: %zu SLAM_ANCHORS, %lld refused\n", kClients,
              listener.anchors.size(), static_cast<long long>(refused));
  EXPECT_LE(listener.anchors.size(), 40u) << node.Output();
  EXPECT_GE(refused, kClients - 40);
  const auto after = std::distance(listener.poses.lower_bound(split_utime), listener.poses.end());
  EXPECT_GE(after, 60) << node.Output();
}

// A corrupt state file (a truncated old-format graph) is refused with one clear line and set
// aside; the node maps from scratch instead of exiting at every restart.
TEST_F(SlamNodeTest, ACorruptStateFileGivesACleanStart) {
  const std::vector<Event> events = LoadIntelPrefix(60);
  const std::string state = ::testing::TempDir() + "/slam_node_corrupt.pg";
  std::remove((state + ".corrupt").c_str());
  std::ofstream(state, std::ios::binary | std::ios::trunc) << "SARMAPPG\x01\x00\x00\x00garbage";
  testing::Process node(
      {"sarmap-slam", "--config", "", "--set", "state_file=" + state, "--set", "resume=true"},
      ::testing::TempDir() + "/slam_node_corrupt.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  Publish(&lcm, events, 0, events.size(), 40, &sent_s);
  HandleFor(&lcm, 1.0);
  EXPECT_TRUE(node.Running()) << node.Output();
  StopCleanly(node);
  EXPECT_NE(node.Output().find("not resumed"), std::string::npos) << node.Output();
  EXPECT_TRUE(std::ifstream(state + ".corrupt").good());
  std::lock_guard<std::mutex> lock(listener.mu);
  EXPECT_GE(listener.poses.size(), 40u) << node.Output();
}

}  // namespace
}  // namespace sarmap
