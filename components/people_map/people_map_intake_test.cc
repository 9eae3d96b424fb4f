// sarmap-people-map's input handling without the bus: capture-time order, the pose
// interpolated at each detection's time, detections waiting for a later pose.
#include "people_map/people_map_intake.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/robot_config.h"
#include "people_map/people_map_test_util.h"

namespace sarmap {
namespace people_map {
namespace {

using common::Utime;

using testing_util::PoseAlongX;
using testing_util::Seen;

struct Fixture {
  PeopleMapNodeOptions options;
  PeopleMap map{PeopleMapOptions()};
  int applied = 0;
  Utime last_applied = 0;
  std::vector<sarmap::slam_anchor_request_t> requests;
  std::unique_ptr<PeopleMapIntake> intake;
  Fixture() {
    const common::RobotOptions robot;
    intake = std::make_unique<PeopleMapIntake>(
        options, robot.base_from_camera.ToRigid3d(), robot.base_from_mic_array.ToRigid3d(), &map,
        [this](Utime u) {
          ++applied;
          last_applied = u;
        },
        [this](sarmap::slam_anchor_request_t& r) { requests.push_back(r); });
  }
  double camera_ahead_m() const {
    return common::RobotOptions().base_from_camera.ToRigid3d().translation().x();
  }
};

TEST(PeopleMapIntakeTest, PlacesADetectionWithThePoseInterpolatedAtItsTime) {
  Fixture f;
  f.intake->OnPose(PoseAlongX(1'000'000, 0.0));
  // Seen at 1.05 s, before the pose of 1.1 s arrives: it waits for it, then is placed halfway.
  f.intake->OnSeen(Seen(1'050'000, 2.0));
  for (Utime u = 1'100'000; u <= 2'000'000; u += 100'000)
    f.intake->OnPose(PoseAlongX(u, 0.1 * (u - 1'000'000) / 100'000));
  ASSERT_EQ(f.map.people().size(), 1u);
  const Person& p = f.map.people().begin()->second;
  EXPECT_NEAR(p.position_m.x(), 0.05 + f.camera_ahead_m() + 2.0, 1e-6);
  EXPECT_NEAR(p.position_m.y(), 0.0, 1e-6);
  EXPECT_EQ(f.applied, 1);
  EXPECT_EQ(f.last_applied, 1'050'000);
  EXPECT_EQ(f.intake->without_pose(), 0);
  const sarmap::people_map_t msg = PeopleMapMessage(f.map.Report(f.last_applied), f.last_applied);
  ASSERT_EQ(msg.num_people, 1);
  EXPECT_EQ(msg.people[0].cues, static_cast<int8_t>(mapped_person_t::CUE_SEEN_DEPTH));
}

// Detections released together (the reorder queue lets them go at one pose) change the map
// once: one on_applied (one PEOPLE_MAP), stamped with the newest of them, not one per detection.
TEST(PeopleMapIntakeTest, ABatchReleasedTogetherIsOneSnapshot) {
  Fixture f;
  f.intake->OnPose(PoseAlongX(1'000'000, 0.0));
  for (Utime u = 1'020'000; u <= 1'100'000; u += 20'000) f.intake->OnSeen(Seen(u, 2.0));
  f.intake->OnPose(PoseAlongX(1'400'000, 0.0));  // every detection is posed, none due yet
  EXPECT_EQ(f.applied, 0);
  f.intake->OnPose(PoseAlongX(1'610'000, 0.0));  // the queue's clock passes all five
  EXPECT_EQ(f.applied, 1);
  EXPECT_EQ(f.last_applied, 1'100'000);
  ASSERT_EQ(f.map.people().size(), 1u);
  EXPECT_EQ(f.intake->without_pose(), 0);
  f.intake->OnPose(PoseAlongX(1'700'000, 0.0));  // nothing new applied: no snapshot
  EXPECT_EQ(f.applied, 1);
}

TEST(PeopleMapIntakeTest, DropsADetectionNoPoseCovers) {
  Fixture f;
  // No pose within max_pose_gap_s (0.5 s) of 5 s: POSE jumps from 1 s to 10 s.
  f.intake->OnPose(PoseAlongX(1'000'000, 0.0));
  f.intake->OnSeen(Seen(5'000'000, 2.0));
  f.intake->OnPose(PoseAlongX(10'000'000, 1.0));
  f.intake->Finish();
  EXPECT_TRUE(f.map.people().empty());
  EXPECT_EQ(f.intake->without_pose(), 1);
}

TEST(PeopleMapIntakeTest, FinishDropsWhatStillWaitsForAPose) {
  Fixture f;
  f.intake->OnPose(PoseAlongX(1'000'000, 0.0));
  f.intake->OnSeen(Seen(1'200'000, 2.0));  // newer than every pose: never placed by extrapolation
  f.intake->Finish();
  EXPECT_TRUE(f.map.people().empty());
  EXPECT_EQ(f.intake->without_pose(), 1);
}

TEST(PeopleMapIntakeTest, ASeenPersonHangsFromItsSlamNodeAndFollowsItsCorrection) {
  Fixture f;
  // Node 3 is made by the scan at 1 s (x = 0); node 4 by the scan at 2 s (x = 1).
  for (Utime u = 1'000'000; u <= 3'000'000; u += 100'000) {
    pose_t m = PoseAlongX(u, 1e-6 * static_cast<double>(u - 1'000'000));
    m.node_id = u < 2'000'000 ? 3 : 4;
    f.intake->OnPose(m);
    if (u == 1'500'000) f.intake->OnSeen(Seen(u, 2.0));  // seen from x = 0.5, node 3
  }
  ASSERT_EQ(f.map.people().size(), 1u);
  const Person& p = f.map.people().begin()->second;
  EXPECT_EQ(p.anchor_node_id, 3);
  // SLAM is asked to keep node 3, with the client id.
  ASSERT_FALSE(f.requests.empty());
  EXPECT_EQ(f.requests.back().node_ids, std::vector<int64_t>{3});
  EXPECT_EQ(f.requests.back().num_node_ids, 1);
  EXPECT_EQ(f.requests.back().client_id, f.options.client_id);
  const Eigen::Vector3d before = p.position_m;
  // An optimisation moves node 3 by +0.4 m in y (its first pose was (0, 0, 0)).
  sarmap::slam_anchors_t a{};
  a.header.utime = 3'000'000;
  a.current.node_id = 4;
  a.current.x_m = 1.0;
  sarmap::slam_anchor_t n3{};
  n3.node_id = 3;
  n3.y_m = 0.4;
  a.anchors.push_back(n3);
  a.num_anchors = 1;
  ASSERT_TRUE(f.intake->OnAnchors(a));
  f.intake->Finish();
  EXPECT_NEAR(p.position_m.x(), before.x(), 1e-9);
  EXPECT_NEAR(p.position_m.y(), before.y() + 0.4, 1e-9);
  // A node pose that is not finite is refused and moves nobody.
  n3.y_m = NAN;
  a.anchors[0] = n3;
  EXPECT_FALSE(f.intake->OnAnchors(a));
  f.intake->Finish();
  EXPECT_NEAR(p.position_m.y(), before.y() + 0.4, 1e-9);
}

TEST(PeopleMapIntakeTest, ASlamRestartedWithANewGraphMovesNobody) {
  Fixture f;
  // Seen from node 40 of the first graph.
  for (Utime u = 1'000'000; u <= 2'000'000; u += 100'000) {
    pose_t m = PoseAlongX(u, 0.0);
    m.node_id = 40;
    f.intake->OnPose(m);
    if (u == 1'200'000) f.intake->OnSeen(Seen(u, 2.0));
  }
  // SLAM restarts without its state: its nodes are numbered from 0 again, node 40 comes later
  // somewhere else.
  for (Utime u = 2'100'000; u <= 3'000'000; u += 100'000) {
    pose_t m = PoseAlongX(u, 0.0);
    m.node_id = 0;
    f.intake->OnPose(m);
  }
  EXPECT_EQ(f.intake->slam_restarts(), 1);
  ASSERT_EQ(f.map.people().size(), 1u);
  const Person& p = f.map.people().begin()->second;
  const Eigen::Vector3d before = p.position_m;
  EXPECT_EQ(p.anchor_node_id, -1);
  EXPECT_TRUE(f.requests.back().node_ids.empty());  // SLAM is asked to keep nothing
  sarmap::slam_anchors_t a{};
  a.header.utime = 3'000'000;
  a.current.node_id = 40;
  a.current.x_m = 5.0;
  ASSERT_TRUE(f.intake->OnAnchors(a));
  f.intake->Finish();
  EXPECT_NEAR((p.position_m - before).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace people_map
}  // namespace sarmap
