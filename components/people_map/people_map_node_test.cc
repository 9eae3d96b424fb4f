// PeopleMapNode in-process over memq://: what it publishes for what it receives, its stamp
// gates, and its state across a restart.
#include "people_map/people_map_node.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/robot_config.h"
#include "people_map/people_map_test_util.h"

namespace sarmap {
namespace people_map {
namespace {

using common::Utime;
using testing_util::PoseAlongX;
using testing_util::Seen;

struct Bus {
  common::Node node{"people_map_node_test", "memq://"};
  std::vector<people_map_t> maps;
  common::Node::Publisher<pose_t> pose_pub = node.Advertise<pose_t>("POSE");
  common::Node::Publisher<people_detections_t> seen_pub =
      node.Advertise<people_detections_t>("PEOPLE_VISUAL");
  Bus() {
    node.Subscribe<people_map_t>("PEOPLE_MAP",
                                 [this](const people_map_t& m, const auto&) { maps.push_back(m); });
  }
  // POSE: the robot at (x_m, 0) at `utime`.
  void PublishPose(Utime utime, double x_m) {
    pose_t m = PoseAlongX(utime, x_m);
    pose_pub.Publish(&m);
  }
  // POSE every 0.1 s from 1.1 s to 2 s: the robot driving along x at 1 m/s from x = 0 at 1 s.
  void PublishDrivingAlongX() {
    for (Utime u = 1'100'000; u <= 2'000'000; u += 100'000)
      PublishPose(u, 0.1 * (u - 1'000'000) / 100'000);
  }
  // PEOPLE_VISUAL: one person `forward_m` ahead of the camera at `utime`.
  void PublishSeen(Utime utime, double forward_m) {
    people_detections_t m = Seen(utime, forward_m);
    seen_pub.Publish(&m);
  }
  // Handles what is queued and runs due timers for `seconds`.
  void Spin(double seconds) {
    for (int i = 0; i < static_cast<int>(seconds / 0.01); ++i) node.SpinOnce(0.01);
  }
  // Spins until `done()` or `timeout_s` of wall time (a loaded machine may need more than the
  // few timer periods the node takes).
  template <class Done>
  bool SpinUntil(Done done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done() && std::chrono::steady_clock::now() < end) node.SpinOnce(0.01);
    return done();
  }
};

PeopleMapNodeOptions FastOptions() {
  PeopleMapNodeOptions options;
  options.publish_period_s = 0.02;
  options.save_period_s = 0.02;
  return options;
}

double CameraAheadM() {
  return common::LoadRobot(PeopleMapNodeOptions().robot_config)
      .base_from_camera.ToRigid3d()
      .translation()
      .x();
}

TEST(PeopleMapNodeTest, PublishesThePersonSeenWithThePoseAtItsTime) {
  Bus bus;
  PeopleMapNode adapter(FastOptions(), &bus.node);
  bus.PublishPose(1'000'000, 0.0);
  bus.Spin(0.05);
  // Seen at 1.05 s, before the pose of 1.1 s: it waits for that pose, then is placed halfway.
  bus.PublishSeen(1'050'000, 2.0);
  bus.PublishDrivingAlongX();
  bus.Spin(0.2);
  ASSERT_FALSE(bus.maps.empty());
  const people_map_t& last = bus.maps.back();
  ASSERT_EQ(last.num_people, 1);
  EXPECT_NEAR(last.people[0].position_m[0], 0.05 + CameraAheadM() + 2.0, 1e-6);
  EXPECT_NEAR(last.people[0].position_m[1], 0.0, 1e-6);
  EXPECT_EQ(last.header.utime, 1'050'000);
  EXPECT_EQ(bus.node.stats().at("POSE").received, 11);
}

TEST(PeopleMapNodeTest, AStampFarAheadIsRejectedAndMovesNothing) {
  Bus bus;
  PeopleMapNode adapter(FastOptions(), &bus.node);
  bus.PublishPose(1'000'000, 0.0);
  bus.Spin(0.05);
  // A year ahead: the gate drops it, so the detection below still finds the poses around it.
  bus.PublishPose(1'000'000 + 365LL * 86400 * 1'000'000, 50.0);
  bus.PublishSeen(1'050'000, 2.0);
  bus.PublishDrivingAlongX();
  bus.Spin(0.2);
  EXPECT_EQ(bus.node.stats().at("POSE").dropped_malformed, 1);
  ASSERT_EQ(adapter.map().people().size(), 1u);
  EXPECT_NEAR(adapter.map().people().begin()->second.position_m.x(), 0.05 + CameraAheadM() + 2.0,
              1e-6);
}

TEST(PeopleMapNodeTest, AsksSlamForTheNodeOfASeenPersonAndMovesThemWithIt) {
  Bus bus;
  std::vector<slam_anchor_request_t> requests;
  bus.node.Subscribe<slam_anchor_request_t>(
      "SLAM_ANCHOR_REQUEST",
      [&requests](const slam_anchor_request_t& m, const auto&) { requests.push_back(m); });
  auto anchors_pub = bus.node.Advertise<slam_anchors_t>("SLAM_ANCHORS");
  PeopleMapNode adapter(FastOptions(), &bus.node);
  for (Utime u = 1'000'000; u <= 2'000'000; u += 100'000) {
    auto pose = PoseAlongX(u, 0.0);
    pose.node_id = 11;
    bus.pose_pub.Publish(&pose);
    if (u == 1'200'000) bus.PublishSeen(u, 2.0);
  }
  ASSERT_TRUE(bus.SpinUntil([&] { return !requests.empty(); }, 5.0));
  EXPECT_EQ(requests.back().client_id, "sarmap-people-map");
  EXPECT_EQ(requests.back().node_ids, std::vector<int64_t>{11});
  // SLAM moves node 11 by 0.3 m along x: so does the person.
  slam_anchors_t a{};
  a.header.utime = 2'000'000;
  a.current.node_id = 11;
  a.current.x_m = 0.3;
  a.covariance_dim = 3;  // [current] only
  a.covariance.assign(3, std::vector<double>(3, 0.0));
  for (int i = 0; i < 3; ++i) a.covariance[i][i] = 1e-4;
  anchors_pub.Publish(&a);
  auto later = PoseAlongX(3'000'000, 0.3);
  later.node_id = 12;
  bus.pose_pub.Publish(&later);
  ASSERT_TRUE(bus.SpinUntil(
      [&] {
        return !bus.maps.empty() && bus.maps.back().num_people == 1 &&
               std::abs(bus.maps.back().people[0].position_m[0] - (0.3 + CameraAheadM() + 2.0)) <
                   1e-6;
      },
      5.0));
  EXPECT_EQ(bus.node.stats().at("SLAM_ANCHORS").dropped_malformed, 0);
}

TEST(PeopleMapNodeTest, ARestartedNodePublishesThePeopleItSavedAtOnce) {
  char dir_template[] = "/tmp/people_map_node_test.XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  PeopleMapNodeOptions options = FastOptions();
  options.state_file = std::string(dir_template) + "/people.state";
  {
    Bus bus;
    PeopleMapNode adapter(options, &bus.node);
    bus.PublishPose(1'000'000, 0.0);
    bus.PublishSeen(1'050'000, 2.0);
    bus.PublishPose(1'100'000, 0.1);
    bus.Spin(0.1);
    adapter.Finish();
    ASSERT_EQ(adapter.map().people().size(), 1u);
  }
  Bus bus;
  PeopleMapNode restarted(options, &bus.node);
  EXPECT_EQ(restarted.map().people().size(), 1u);
  // No input at all: the saved person is on the bus at the first publish period.
  ASSERT_TRUE(bus.SpinUntil([&] { return !bus.maps.empty(); }, 5.0));
  EXPECT_EQ(bus.maps.back().num_people, 1);
  EXPECT_EQ(bus.maps.back().header.utime, 1'050'000);

  // A corrupt state file: set aside, an empty map, no crash.
  FILE* f = fopen(options.state_file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  fputs("not a state file\n", f);
  fclose(f);
  Bus bus2;
  PeopleMapNode clean(options, &bus2.node);
  EXPECT_TRUE(clean.map().people().empty());
  std::filesystem::remove_all(dir_template);
}

}  // namespace
}  // namespace people_map
}  // namespace sarmap
