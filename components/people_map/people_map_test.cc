#include "people_map/people_map.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <fstream>
#include <sstream>

#include "common/robot_config.h"
#include "common/state_file.h"

namespace sarmap {
namespace people_map {
namespace {

using common::Rigid2d;
using common::Rigid3d;

// The default robot: camera optical frame 0.55 m up, looking along base +x.
Rigid3d MapFromCamera(const Rigid2d& map_from_base) {
  return Rigid3d::FromRigid2d(map_from_base) * common::RobotOptions().base_from_camera.ToRigid3d();
}

SeenDetection PersonAhead(double forward_m, double right_m) {
  SeenDetection d;
  // Camera optical frame: z forward, x right, y down; the person's centre 0.85 m above the floor.
  d.position_camera_m = Eigen::Vector3d(right_m, 0.55 - 0.85, forward_m);
  d.covariance_camera = Eigen::Vector3d(0.01, 0.01, 0.03).asDiagonal();
  d.confidence = 0.9;
  return d;
}

TEST(PeopleMapTest, SeenPersonLandsInTheMapFrame) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d map_from_base(2.0, 1.0, M_PI / 2);  // facing +y
  map.AddSeen(1'000'000, {PersonAhead(2.0, 0.0)}, MapFromCamera(map_from_base),
              Eigen::Matrix3d::Zero(), map_from_base.translation());
  ASSERT_EQ(map.people().size(), 1u);
  const Person& p = map.people().begin()->second;
  EXPECT_NEAR(p.position_m.x(), 2.0, 1e-9);
  EXPECT_NEAR(p.position_m.y(), 1.0 + 0.1 + 2.0, 1e-9);  // camera 0.10 m ahead of the base
  EXPECT_NEAR(p.position_m.z(), 0.85, 1e-9);
  EXPECT_EQ(p.cues, kSeenRgbd);
}

TEST(PeopleMapTest, MergesWithin45cmAndCountsPeoplePerPlace) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d a(0, 0, 0), b(1.0, 0.5, 0.2);
  // The same person seen from two poses, 20 cm of error between them.
  map.AddSeen(1'000'000, {PersonAhead(3.0, 0.0)}, MapFromCamera(a), Eigen::Matrix3d::Zero(),
              a.translation());
  const Eigen::Vector3d first = map.people().begin()->second.position_m;
  const Eigen::Vector3d target_in_b =
      (MapFromCamera(b).inverse() * (first + Eigen::Vector3d(0.2, 0, 0)));
  SeenDetection again = PersonAhead(0, 0);
  again.position_camera_m = target_in_b;
  map.AddSeen(2'000'000, {again}, MapFromCamera(b), Eigen::Matrix3d::Zero(), b.translation());
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.num_detections, 2);
  // Two people 1 m apart are two; two within 30 cm in one frame are one place with a count of 2.
  map.AddSeen(3'000'000, {PersonAhead(3.0, 1.2)}, MapFromCamera(a), Eigen::Matrix3d::Zero(),
              a.translation());
  EXPECT_EQ(map.people().size(), 2u);
  map.AddSeen(4'000'000, {PersonAhead(2.0, -2.0), PersonAhead(2.0, -2.3)}, MapFromCamera(a),
              Eigen::Matrix3d::Zero(), a.translation());
  ASSERT_EQ(map.people().size(), 3u);
  EXPECT_EQ(map.people().rbegin()->second.people_count, 2);
}

// One person, two sightings (two tracks of the detector, 40 s apart): the second with a robot
// pose 0.4 m off (SLAM drift, within the 45 cm of one place) and three times as many frames.
// Every frame of a sighting shares its pose error, so the frames must not outvote the first
// sighting: the person ends between the two, not where the last frames put them.
TEST(PeopleMapTest, ALaterSightingWithADriftedPoseDoesNotDragThePerson) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d first_pose(0, 0, 0);
  const Eigen::Vector2d truth_xy(3.1, 0.0);  // the camera 0.10 m ahead of the base
  // The drifted pose: the robot believes it is 0.4 m further left (+y) than it is.
  const Rigid2d true_second(1.0, -1.0, 0.5), believed_second(1.0, -0.6, 0.5);
  const Eigen::Matrix3d pose_cov = Eigen::Vector3d(0.03 * 0.03, 0.03 * 0.03, 0.0001).asDiagonal();
  common::Utime t = 1'000'000;
  for (int i = 0; i < 20; ++i, t += 66'000) {
    SeenDetection d = PersonAhead(3.0, (i % 2 ? 0.02 : -0.02));  // a little sensor noise
    d.track_id = 1;
    map.AddSeen(t, {d}, MapFromCamera(first_pose), pose_cov, first_pose.translation());
  }
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_LT((map.people().begin()->second.position_m.head<2>() - truth_xy).norm(), 0.05);
  t += 40'000'000;
  // The person as the second camera pose truly sees them.
  const Eigen::Vector3d truth_map(truth_xy.x(), truth_xy.y(), 0.85);
  SeenDetection second = PersonAhead(0, 0);
  second.position_camera_m = MapFromCamera(true_second).inverse() * truth_map;
  second.track_id = 7;
  for (int i = 0; i < 60; ++i, t += 66'000) {
    map.AddSeen(t, {second}, MapFromCamera(believed_second), pose_cov,
                believed_second.translation());
  }
  ASSERT_EQ(map.people().size(), 1u);
  const Person& p = map.people().begin()->second;
  EXPECT_EQ(p.num_detections, 80);
  const double error_m = (p.position_m.head<2>() - truth_xy).norm();
  // Each frame fused as if independent ended at the drifted place (0.4 m off); two sightings of
  // equal weight end half way.
  EXPECT_LT(error_m, 0.25);
  EXPECT_GT(error_m, 0.1);
}

// SLAM's pose error changes between two sightings by more than its covariance shows (0.22-0.27
// m per axis on the generated sites): a person seen again 0.65 m from where the first sighting
// put them is the same person, not a second one. Two people 0.65 m apart in one frame share the
// frame's pose error: they stay two.
TEST(PeopleMapTest, ANewSightingWithinThePoseDriftIsTheSamePerson) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d pose(0, 0, 0);
  const Eigen::Matrix3d pose_cov = Eigen::Vector3d(0.03 * 0.03, 0.03 * 0.03, 0.0001).asDiagonal();
  common::Utime t = 1'000'000;
  for (int i = 0; i < 10; ++i, t += 66'000) {
    SeenDetection d = PersonAhead(3.0, 0.0);
    d.track_id = 1;
    map.AddSeen(t, {d}, MapFromCamera(pose), pose_cov, pose.translation());
  }
  // 30 s later, a new track: the same person, placed 0.65 m to the side by the drifted pose.
  t += 30'000'000;
  SeenDetection again = PersonAhead(3.0, 0.65);
  again.track_id = 2;
  map.AddSeen(t, {again}, MapFromCamera(pose), pose_cov, pose.translation());
  EXPECT_EQ(map.people().size(), 1u);
  // Two people 0.65 m apart in one frame.
  t += 30'000'000;
  const Rigid2d elsewhere(0, 10, 0);
  SeenDetection left = PersonAhead(3.0, -0.3), right = PersonAhead(3.0, 0.35);
  left.track_id = 3;
  right.track_id = 4;
  map.AddSeen(t, {left, right}, MapFromCamera(elsewhere), pose_cov, elsewhere.translation());
  EXPECT_EQ(map.people().size(), 3u);
  // Without the drift model the 0.65 m sighting is a second person.
  PeopleMapOptions no_drift;
  no_drift.relative_pose_sigma_m = 0;
  PeopleMap strict{no_drift};
  SeenDetection first = PersonAhead(3.0, 0.0);
  first.track_id = 1;
  strict.AddSeen(1'000'000, {first}, MapFromCamera(pose), pose_cov, pose.translation());
  strict.AddSeen(31'000'000, {again}, MapFromCamera(pose), pose_cov, pose.translation());
  EXPECT_EQ(strict.people().size(), 2u);
}

TEST(PeopleMapTest, PoseUncertaintyGrowsTheCovarianceAcrossTheBearing) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d pose(0, 0, 0);
  Eigen::Matrix3d pose_cov = Eigen::Matrix3d::Zero();
  pose_cov(2, 2) = 0.05 * 0.05;  // yaw only
  map.AddSeen(1, {PersonAhead(4.0, 0.0)}, MapFromCamera(pose), pose_cov, pose.translation());
  const Eigen::Matrix3d& P = map.people().begin()->second.covariance;
  // Along the bearing (x): camera range noise 0.03; across (y): 0.01 + (4.1 * 0.05)^2.
  EXPECT_NEAR(P(0, 0), 0.03, 1e-6);
  EXPECT_NEAR(P(1, 1), 0.01 + std::pow(4.1 * 0.05, 2), 1e-6);
}

TEST(PeopleMapTest, HeardPersonTakesItsRangeFromTheSoundMapAndFusesWithASeenOne) {
  PeopleMapOptions options;
  options.min_heard_calls = 1;  // one call places a person (the default asks for two)
  PeopleMap map(options);
  SoundSource hidden;  // behind furniture: never seen
  hidden.id = 7;
  hidden.position_m = Eigen::Vector3d(4.0, 3.0, 0.5);
  hidden.covariance = Eigen::Vector3d(0.04, 0.04, 0.1).asDiagonal();
  SoundSource visible;
  visible.id = 8;
  visible.position_m = Eigen::Vector3d(3.1, -0.1, 1.0);
  visible.covariance = Eigen::Vector3d(0.09, 0.09, 0.2).asDiagonal();
  hidden.converged = visible.converged = true;
  hidden.is_person = visible.is_person = true;  // voices
  map.UpdateSoundSources(1'000'000, {hidden, visible});
  EXPECT_TRUE(map.people().empty());  // sources are not people until heard calling

  // The array at the origin hears "help" in the direction of the hidden source.
  HeardDetection call;
  call.azimuth_rad = std::atan2(3.0, 4.0) + 0.02;
  call.azimuth_sigma_rad = 0.05;
  call.keyword = "help";
  call.confidence = 0.8;
  EXPECT_EQ(map.AddHeard(2'000'000, {call}, Rigid3d()), 1);
  ASSERT_EQ(map.people().size(), 1u);
  const Person& heard = map.people().begin()->second;
  EXPECT_EQ(heard.sound_source_id, 7);
  EXPECT_EQ(heard.keyword, "help");
  EXPECT_NEAR((heard.position_m - hidden.position_m).norm(), 0.0, 1e-9);  // not 0.95 m away

  // A direction that points at nothing is not placed.
  HeardDetection stray = call;
  stray.azimuth_rad = -2.0;
  EXPECT_EQ(map.AddHeard(2'100'000, {stray}, Rigid3d()), 0);

  // Seen and heard agree about the visible one: one person with both cues, fused in between.
  const Rigid2d pose(0, 0, 0);
  map.AddSeen(3'000'000, {PersonAhead(2.9, 0.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
              pose.translation());
  HeardDetection talk;
  talk.azimuth_rad = std::atan2(-0.1, 3.1);
  talk.confidence = 0.7;
  map.AddHeard(3'100'000, {talk}, Rigid3d());
  ASSERT_EQ(map.people().size(), 2u);
  const Person& both = map.people().rbegin()->second;
  EXPECT_EQ(both.cues, kSeenRgbd | kHeard);
  EXPECT_EQ(both.sound_source_id, 8);
  EXPECT_GT(both.position_m.x(), 3.0 - 1e-9);  // seen at 3.0, heard at 3.1
  EXPECT_LT(both.position_m.x(), 3.05);        // the seen estimate is the more certain
}

// An initialising source's position is a guess: a call heard towards it is remembered, and the
// person is placed only once the sound map says the source has converged.
PeopleMapOptions OneCallIsAPerson() {
  PeopleMapOptions options;
  options.min_heard_calls = 1;
  return options;
}

// A voice (a source the sound map calls a person) at (x, y, z) with diagonal position variances
// (m^2).
SoundSource SourceAt(int64_t id, const Eigen::Vector3d& position_m,
                     const Eigen::Vector3d& variances_m2, bool converged) {
  SoundSource s;
  s.id = id;
  s.is_person = true;
  s.position_m = position_m;
  s.covariance = variances_m2.asDiagonal();
  s.converged = converged;
  return s;
}

// "help" heard from the array at the origin, looking along x.
HeardDetection HelpCallTowards(double x_m, double y_m) {
  HeardDetection call;
  call.azimuth_rad = std::atan2(y_m, x_m);
  call.keyword = "help";
  call.confidence = 0.9;
  return call;
}

TEST(PeopleMapTest, HeardPersonWaitsForItsSoundSourceToConverge) {
  PeopleMap map(OneCallIsAPerson());
  SoundSource caller;
  caller.id = 3;
  caller.is_person = true;
  caller.position_m = Eigen::Vector3d(2.0, 5.0, 0.5);
  caller.covariance = Eigen::Vector3d(4.0, 4.0, 1.0).asDiagonal();
  map.UpdateSoundSources(1'000'000, {caller});
  HeardDetection call;
  call.azimuth_rad = std::atan2(5.0, 2.0);
  call.keyword = "help";
  call.confidence = 0.9;
  EXPECT_EQ(map.AddHeard(2'000'000, {call}, Rigid3d()), 1);  // points at the source...
  EXPECT_TRUE(map.people().empty());                         // ...which is still a guess
  map.UpdateSoundSources(3'000'000, {caller});
  EXPECT_TRUE(map.people().empty());

  caller.position_m = Eigen::Vector3d(2.2, 4.6, 0.5);
  caller.covariance = Eigen::Vector3d(0.04, 0.04, 0.1).asDiagonal();
  caller.converged = true;
  map.UpdateSoundSources(4'000'000, {caller});
  ASSERT_EQ(map.people().size(), 1u);
  const Person& p = map.people().begin()->second;
  EXPECT_EQ(p.sound_source_id, 3);
  EXPECT_EQ(p.keyword, "help");
  EXPECT_NEAR((p.position_m - caller.position_m).norm(), 0.0, 1e-9);

  // Converged long after the call (outside heard_person_window_s): not a person.
  PeopleMap late(OneCallIsAPerson());
  caller.converged = false;
  late.UpdateSoundSources(1'000'000, {caller});
  late.AddHeard(2'000'000, {call}, Rigid3d());
  caller.converged = true;
  late.UpdateSoundSources(60'000'000, {caller});
  EXPECT_TRUE(late.people().empty());
}

// With heard_max_source_sigma_m, a source known to within that std places the person before
// the sound map calls it converged; a wider one still waits.
TEST(PeopleMapTest, HeardPersonIsPlacedAtASourceKnownWellEnough) {
  PeopleMapOptions options = OneCallIsAPerson();
  options.heard_max_source_sigma_m = 0.6;
  const HeardDetection call = HelpCallTowards(2.0, 5.0);
  SoundSource caller;
  caller.id = 3;
  caller.is_person = true;
  caller.position_m = Eigen::Vector3d(2.0, 5.0, 0.5);
  // Largest planar std 0.65 m along a tilted axis (eigenvalues 0.4225 and 0.04): not yet.
  const double a = 0.5 * (0.4225 + 0.04), b = 0.5 * (0.4225 - 0.04);
  caller.covariance << a, b, 0, b, a, 0, 0, 0, 1;
  PeopleMap map(options);
  map.UpdateSoundSources(1'000'000, {caller});
  EXPECT_EQ(map.AddHeard(2'000'000, {call}, Rigid3d()), 1);
  EXPECT_TRUE(map.people().empty());
  // 0.5 m: placed, though not converged.
  const double c = 0.5 * (0.25 + 0.04), d = 0.5 * (0.25 - 0.04);
  caller.covariance << c, d, 0, d, c, 0, 0, 0, 1;
  map.UpdateSoundSources(3'000'000, {caller});
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 3);
}

// A source known only to tens of degrees (the sound map's just-born or runaway sources) lies in
// every direction's gate. It must not take a call, nor make a call towards the real caller
// "ambiguous".
TEST(PeopleMapTest, ASourceOfUnknownDirectionNeitherTakesNorBlocksACall) {
  PeopleMap map(OneCallIsAPerson());
  const SoundSource caller = SourceAt(2, {6.8, -2.4, 0.6}, {0.04, 0.04, 0.1}, true);
  const SoundSource runaway = SourceAt(9, {777.0, 633.0, 0.6}, {3e9, 2e9, 1.0}, false);
  map.UpdateSoundSources(1'000'000, {caller, runaway});
  EXPECT_EQ(map.AddHeard(2'000'000, {HelpCallTowards(6.8, -2.4)}, Rigid3d()), 1);
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 2);
}

// Along a corridor two sources can lie on one bearing: a call from that bearing names neither.
TEST(PeopleMapTest, HeardDirectionThroughTwoSourcesMakesNoPerson) {
  PeopleMap map(OneCallIsAPerson());
  const SoundSource near_source = SourceAt(1, {4.0, 0.1, 0.5}, {0.01, 0.01, 0.1}, true);
  const SoundSource far_source = SourceAt(2, {7.0, 0.1, 0.5}, {0.01, 0.01, 0.1}, true);
  map.UpdateSoundSources(1'000'000, {near_source, far_source});
  HeardDetection call;
  call.azimuth_rad = 0.02;
  call.keyword = "here";
  call.confidence = 0.9;
  EXPECT_EQ(map.AddHeard(2'000'000, {call}, Rigid3d()), 1);
  EXPECT_TRUE(map.people().empty());
  map.UpdateSoundSources(3'000'000, {near_source, far_source});  // nor later, as "recently heard"
  EXPECT_TRUE(map.people().empty());

  // From the side the two are told apart, and the far one is the caller.
  const Rigid3d beside(Eigen::Vector3d(7.0, -3.0, 0.0), Eigen::Quaterniond::Identity());
  call.azimuth_rad = M_PI / 2;
  EXPECT_EQ(map.AddHeard(4'000'000, {call}, beside), 1);
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 2);
}

// One keyword false alarm is not a person: by default a source needs two calls within

// Only voices become people: calls towards a source the sound map classes otherwise (a machine
// the keyword spotter fires on) make nobody, until the sound map calls the source a voice.
TEST(PeopleMapTest, CallsTowardsASourceThatIsNoVoiceMakeNoPerson) {
  PeopleMap map(PeopleMapOptions{});
  SoundSource machine = SourceAt(5, {3.0, 3.0, 0.5}, {0.02, 0.02, 0.1}, true);
  machine.is_person = false;
  map.UpdateSoundSources(1'000'000, {machine});
  const HeardDetection call = HelpCallTowards(3.0, 3.0);
  for (int64_t utime : {2'000'000, 8'000'000, 14'000'000}) {
    EXPECT_EQ(map.AddHeard(utime, {call}, Rigid3d()), 1);
    map.UpdateSoundSources(utime + 500'000, {machine});
  }
  EXPECT_TRUE(map.people().empty());
  // The calls were counted: once the source is a voice, it is a person.
  machine.is_person = true;
  map.UpdateSoundSources(15'000'000, {machine});
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 5);
}

// A person seen 3 m ahead of the robot at the origin; returns where the map put them.
Eigen::Vector3d SeeOnePersonAhead(PeopleMap* map) {
  const Rigid2d pose(0, 0, 0);
  map->AddSeen(1'000'000, {PersonAhead(3.0, 0.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
               pose.translation());
  EXPECT_EQ(map->people().size(), 1u);
  return map->people().empty() ? Eigen::Vector3d::Zero() : map->people().begin()->second.position_m;
}

// The camera places a person from one stretch of the path, the sound map from bearings along
// another; SLAM's pose error changes in between (relative_pose_sigma_m). A seen and a heard
// estimate 0.6 m apart, each precise on its own, are one person, nearer where the camera saw
// them.
TEST(PeopleMapTest, SeenAndHeardApartByPoseDriftAreOnePerson) {
  for (const double drift_sigma_m : {0.27, 0.0}) {
    PeopleMapOptions options;
    options.relative_pose_sigma_m = drift_sigma_m;
    PeopleMap map(options);
    const Eigen::Vector3d seen_m = SeeOnePersonAhead(&map);
    const SoundSource voice =
        SourceAt(6, {seen_m.x() + 0.5, seen_m.y() + 0.35, 0.6}, {0.01, 0.01, 0.1}, true);
    map.UpdateSoundSources(2'000'000, {voice});
    for (int64_t utime : {3'000'000, 9'000'000}) {
      map.AddHeard(utime, {HelpCallTowards(voice.position_m.x(), voice.position_m.y())}, Rigid3d());
      map.UpdateSoundSources(utime + 500'000, {voice});
    }
    if (drift_sigma_m > 0) {
      ASSERT_EQ(map.people().size(), 1u);
      const Person& p = map.people().begin()->second;
      EXPECT_EQ(p.cues, kSeenRgbd | kHeard);
      const double to_seen_m = (p.position_m - seen_m).head<2>().norm();
      EXPECT_LT(to_seen_m, 0.2);
      EXPECT_LT(to_seen_m, (p.position_m - voice.position_m).head<2>().norm());
    } else {
      EXPECT_EQ(map.people().size(), 2u);  // without the drift the two are told apart
    }
  }
}

// heard_person_window_s.
TEST(PeopleMapTest, OneCallIsNotAPersonTwoCallsAre) {
  PeopleMap map(PeopleMapOptions{});
  const SoundSource source = SourceAt(5, {3.0, 3.0, 0.5}, {0.02, 0.02, 0.1}, true);
  map.UpdateSoundSources(1'000'000, {source});
  const HeardDetection call = HelpCallTowards(3.0, 3.0);
  EXPECT_EQ(map.AddHeard(2'000'000, {call}, Rigid3d()), 1);
  map.UpdateSoundSources(3'000'000, {source});
  EXPECT_TRUE(map.people().empty());
  // The next call comes after the window: still one recent call.
  EXPECT_EQ(map.AddHeard(40'000'000, {call}, Rigid3d()), 1);
  map.UpdateSoundSources(41'000'000, {source});
  EXPECT_TRUE(map.people().empty());
  // A second call 6 s later: a person.
  EXPECT_EQ(map.AddHeard(46'000'000, {call}, Rigid3d()), 1);
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 5);
}

// A keyword false alarm on one utterance often fires several keywords within a fraction of a
// second (the open-area mission: "assist", "rescue", "help", "here" 0.1-0.9 s apart towards a
// generator's beam). Those hits are one call, not the two calls a heard person needs.
TEST(PeopleMapTest, SeveralKeywordsOfOneUtteranceAreOneCall) {
  PeopleMap map(PeopleMapOptions{});
  const SoundSource source = SourceAt(4, {3.0, 3.0, 0.5}, {0.02, 0.02, 0.1}, true);
  map.UpdateSoundSources(1'000'000, {source});
  HeardDetection call = HelpCallTowards(3.0, 3.0);
  call.confidence = 0.99;
  for (const auto& [utime, keyword] :
       std::vector<std::pair<int64_t, std::string>>{{2'000'000, "assist"},
                                                    {2'070'000, "rescue"},
                                                    {2'760'000, "help"},
                                                    {2'870'000, "here"}}) {
    call.keyword = keyword;
    EXPECT_EQ(map.AddHeard(utime, {call}, Rigid3d()), 1);
  }
  map.UpdateSoundSources(3'000'000, {source});
  EXPECT_TRUE(map.people().empty());
  // The same source calling again 5 s later: two calls, a person.
  call.keyword = "help";
  EXPECT_EQ(map.AddHeard(8'000'000, {call}, Rigid3d()), 1);
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 4);
  // With same_call_s 0 every hit is a call (the previous behaviour): the burst alone is a person.
  PeopleMapOptions every_hit;
  every_hit.same_call_s = 0;
  PeopleMap old_map(every_hit);
  old_map.UpdateSoundSources(1'000'000, {source});
  old_map.AddHeard(2'000'000, {call}, Rigid3d());
  old_map.AddHeard(2'070'000, {call}, Rigid3d());
  EXPECT_EQ(old_map.people().size(), 1u);
}

// The sound map can split a voice into two sources. The second, further from a seen caller than
// merge_radius_m but within the drift between sighting and hearing, is the same caller.
TEST(PeopleMapTest, ASecondSourceOfASeenCallerJoinsThemWithinTheDrift) {
  for (const double drift_sigma_m : {0.27, 0.0}) {
    PeopleMapOptions options;
    options.relative_pose_sigma_m = drift_sigma_m;
    PeopleMap map(options);
    const Eigen::Vector3d seen_m = SeeOnePersonAhead(&map);
    const SoundSource first =
        SourceAt(1, {seen_m.x() + 0.1, seen_m.y(), 0.6}, {0.01, 0.01, 0.1}, true);
    const SoundSource second =
        SourceAt(2, {seen_m.x() + 0.5, seen_m.y() + 0.35, 0.6}, {0.01, 0.01, 0.1}, true);
    map.UpdateSoundSources(1'500'000, {first, second});
    // Calls towards each source from 0.6 m beyond it (so that the other is out of the gate).
    auto call_towards = [&](const SoundSource& s, int64_t utime) {
      const Rigid3d map_from_mic(s.position_m + Eigen::Vector3d(0.6, 0.0, 0.0),
                                 Eigen::Quaterniond::Identity());
      HeardDetection call = HelpCallTowards(-1.0, 0.0);
      call.azimuth_sigma_rad = 0.02;
      EXPECT_EQ(map.AddHeard(utime, {call}, map_from_mic), 1);
      map.UpdateSoundSources(utime + 100'000, {first, second});
    };
    call_towards(first, 2'000'000);
    call_towards(first, 6'000'000);
    ASSERT_EQ(map.people().size(), 1u);
    EXPECT_EQ(map.people().begin()->second.cues, kSeenRgbd | kHeard);
    call_towards(second, 10'000'000);
    call_towards(second, 14'000'000);
    if (drift_sigma_m > 0) {
      ASSERT_EQ(map.people().size(), 1u);
      EXPECT_EQ(map.people().begin()->second.sound_source_id, 1);
    } else {
      EXPECT_EQ(map.people().size(), 2u);  // 0.61 m apart, beyond merge_radius_m
    }
  }
}

// The sound map can split one voice into two sources a few decimetres apart (bearings from two
// stretches of the path; the open-area mission put frank twice, 0.40 m apart). Two heard people
// within merge_radius_m are one caller; calls towards either stay evidence for that one person.
TEST(PeopleMapTest, TwoSoundSourcesOfOneCallerAreOnePerson) {
  PeopleMap map(PeopleMapOptions{});
  SoundSource first, second;
  first.id = 1;
  first.position_m = Eigen::Vector3d(1.0, 0.0, 0.5);
  second.id = 2;
  second.position_m = Eigen::Vector3d(1.0, 0.4, 0.5);
  first.covariance = second.covariance = Eigen::Vector3d(0.002, 0.002, 0.01).asDiagonal();
  first.converged = second.converged = true;
  first.is_person = second.is_person = true;
  map.UpdateSoundSources(1'000'000, {first, second});
  HeardDetection call;
  call.azimuth_sigma_rad = 0.05;
  call.keyword = "help";
  call.confidence = 0.9;
  auto call_towards = [&](const SoundSource& s, int64_t utime) {
    call.azimuth_rad = std::atan2(s.position_m.y(), s.position_m.x());
    return map.AddHeard(utime, {call}, Rigid3d());
  };
  EXPECT_EQ(call_towards(first, 2'000'000), 1);
  EXPECT_EQ(call_towards(first, 6'000'000), 1);
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(call_towards(second, 10'000'000), 1);
  EXPECT_EQ(call_towards(second, 14'000'000), 1);
  map.UpdateSoundSources(15'000'000, {first, second});
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_EQ(map.people().begin()->second.sound_source_id, 1);
  const int detections = map.people().begin()->second.num_detections;
  EXPECT_EQ(call_towards(second, 18'000'000), 1);
  map.UpdateSoundSources(19'000'000, {first, second});
  ASSERT_EQ(map.people().size(), 1u);
  EXPECT_GT(map.people().begin()->second.num_detections, detections);
  // Further apart than merge_radius_m they are two callers.
  PeopleMap apart(PeopleMapOptions{});
  second.position_m = Eigen::Vector3d(1.0, 0.8, 0.5);
  apart.UpdateSoundSources(1'000'000, {first, second});
  for (int64_t t : {2'000'000, 6'000'000}) {
    call.azimuth_rad = 0.0;
    apart.AddHeard(t, {call}, Rigid3d());
    call.azimuth_rad = std::atan2(0.8, 1.0);
    apart.AddHeard(t + 100'000, {call}, Rigid3d());
  }
  apart.UpdateSoundSources(7'000'000, {first, second});
  EXPECT_EQ(apart.people().size(), 2u);
}

// A planar sound map gives no height (z variance 0): fusing it with a seen person must stay
// finite, and a source with NaN in it is ignored.
TEST(PeopleMapTest, PlanarSoundSourceFusesFiniteAndGarbageSourcesAreIgnored) {
  PeopleMap map(OneCallIsAPerson());
  const Rigid2d pose(0, 0, 0);
  map.AddSeen(1'000'000, {PersonAhead(3.0, 0.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
              pose.translation());
  SoundSource planar;
  planar.id = 4;
  planar.position_m = Eigen::Vector3d(3.1, 0.05, 0.6);
  planar.covariance = Eigen::Matrix3d::Zero();
  planar.covariance.topLeftCorner<2, 2>() = Eigen::Matrix2d::Identity() * 0.04;
  planar.converged = true;
  SoundSource garbage = planar;
  garbage.id = 5;
  garbage.position_m.x() = std::nan("");
  map.UpdateSoundSources(2'000'000, {planar, garbage});
  HeardDetection call;
  call.azimuth_rad = std::atan2(0.05, 3.1);
  call.keyword = "here";
  call.confidence = 0.9;
  EXPECT_EQ(map.AddHeard(3'000'000, {call}, Rigid3d()), 1);
  map.UpdateSoundSources(4'000'000, {planar, garbage});
  ASSERT_EQ(map.people().size(), 1u);
  const Person& both = map.people().begin()->second;
  EXPECT_EQ(both.cues & kHeard, kHeard);
  EXPECT_TRUE(both.position_m.allFinite());
  EXPECT_TRUE(both.covariance.allFinite());
  EXPECT_NEAR(both.position_m.x(), 3.05, 0.1);
  for (const auto& [id, p] : map.people()) EXPECT_NE(p.sound_source_id, 5);
}

TEST(PeopleMapTest, ConfidenceGrowsWithEvidenceAndDecaysWithout) {
  PeopleMapOptions options;
  options.confidence_half_life_s = 10;
  PeopleMap map(options);
  const Rigid2d pose(0, 0, 0);
  double last = 0;
  for (int i = 0; i < 4; ++i) {
    map.AddSeen(1'000'000 * (i + 1), {PersonAhead(2.0, 0.0)}, MapFromCamera(pose),
                Eigen::Matrix3d::Zero(), pose.translation());
    const double c = map.people().begin()->second.confidence;
    EXPECT_GT(c, last);
    last = c;
  }
  const Person& p = map.people().begin()->second;
  EXPECT_NEAR(map.DecayedConfidence(p, p.last_detected_utime + 10'000'000), last / 2, 1e-9);
  EXPECT_EQ(map.Report(p.last_detected_utime).size(), 1u);
  // Four detections made the person sure (>= keep_confidence): reported for good, with its
  // confidence decayed. A person seen once decays off the map; so does everyone when nothing is
  // kept.
  ASSERT_GE(last, options.keep_confidence);
  const common::Utime later = p.last_detected_utime + 100'000'000;
  map.AddSeen(p.last_detected_utime, {PersonAhead(2.0, 3.0)}, MapFromCamera(pose),
              Eigen::Matrix3d::Zero(), pose.translation());
  ASSERT_EQ(map.people().size(), 2u);
  EXPECT_LT(map.people().rbegin()->second.confidence, options.keep_confidence);
  const auto report = map.Report(later);
  ASSERT_EQ(report.size(), 1u);
  EXPECT_EQ(report[0].id, p.id);
  EXPECT_NEAR(report[0].confidence, last / 1024, 1e-9);
  options.keep_confidence = 1.1;
  PeopleMap forgetting(options);
  forgetting.AddSeen(1'000'000, {PersonAhead(2.0, 0.0)}, MapFromCamera(pose),
                     Eigen::Matrix3d::Zero(), pose.translation());
  forgetting.AddSeen(2'000'000, {PersonAhead(2.0, 0.0)}, MapFromCamera(pose),
                     Eigen::Matrix3d::Zero(), pose.translation());
  EXPECT_EQ(forgetting.Report(2'000'000).size(), 1u);
  EXPECT_TRUE(forgetting.Report(102'000'000).empty());
}

// A person only seen is reported once seen in min_seen_detections frames, or seen again
// min_seen_span_s after the first time: a flicker that passed the detector's confirmation for a
// few frames is sure by the confidence (which takes every frame as independent evidence) but not
// on the map; a person heard too is not held back.
TEST(PeopleMapTest, APersonOnlySeenIsReportedOnceSeenInEnoughFrames) {
  PeopleMapOptions options;
  options.min_seen_detections = 10;
  options.min_heard_calls = 1;
  PeopleMap map(options);
  const Rigid2d pose(0, 0, 0);
  const auto see = [&](common::Utime utime, double x, double y) {
    map.AddSeen(utime, {PersonAhead(x, y)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
                pose.translation());
  };
  common::Utime t = 1'000'000;
  for (int i = 0; i < 9; ++i, t += 66'000) see(t, 2.0, 0.0);
  ASSERT_EQ(map.people().size(), 1u);
  const Person& flicker = map.people().begin()->second;
  EXPECT_TRUE(flicker.confirmed);      // nine frames make the confidence sure...
  EXPECT_TRUE(map.Report(t).empty());  // ...but not a person on the map
  see(t, 2.0, 0.0);
  ASSERT_EQ(map.Report(t).size(), 1u);  // the tenth frame does
  EXPECT_EQ(map.Report(t)[0].id, flicker.id);

  // Seen once and heard calling: reported at once.
  const SoundSource voice = SourceAt(5, {3.0, 3.0, 0.5}, {0.02, 0.02, 0.1}, true);
  map.UpdateSoundSources(t, {voice});
  see(t + 100'000, 3.0, -3.0);  // at (3, 3): 3 m ahead, 3 m to the left
  EXPECT_EQ(map.Report(t + 100'000).size(), 1u);
  EXPECT_EQ(map.AddHeard(t + 200'000, {HelpCallTowards(3.0, 3.0)}, Rigid3d()), 1);
  const auto report = map.Report(t + 200'000);
  ASSERT_EQ(report.size(), 2u);
  const Person& caller = report[0].id == flicker.id ? report[1] : report[0];
  EXPECT_EQ(caller.cues & kHeard, kHeard);
  EXPECT_EQ(caller.num_detections, 2);  // seen once, heard once

  // Glimpses (min_seen_span_s 5): three frames, three more 3 s later, then one 6 s after the
  // first: seen again, reported.
  options.min_seen_span_s = 5;
  PeopleMap glimpses(options);
  const auto glimpse = [&](common::Utime utime) {
    glimpses.AddSeen(utime, {PersonAhead(2.0, 0.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
                     pose.translation());
  };
  for (int i = 0; i < 3; ++i) glimpse(1'000'000 + i * 66'000);
  EXPECT_TRUE(glimpses.Report(2'000'000).empty());
  for (int i = 0; i < 3; ++i) glimpse(4'000'000 + i * 66'000);
  EXPECT_TRUE(glimpses.Report(5'000'000).empty());  // 3.1 s after the first: one viewing
  glimpse(7'000'000);
  EXPECT_EQ(glimpses.Report(7'000'000).size(), 1u);
}

// kill -9 of the people map between a hidden caller's two heard calls: the restarted map must
// still count the first, else it needs two more calls, and a caller whose sound source lies 0.16 m
// from her can stay unfound for the rest of a mission killed once.
TEST(PeopleMapTest, CallsHeardBeforeARestartStillCount) {
  const SoundSource source = SourceAt(5, {3.0, 3.0, 0.5}, {0.02, 0.02, 0.1}, true);
  const HeardDetection call = HelpCallTowards(3.0, 3.0);
  PeopleMap before{PeopleMapOptions()};
  before.UpdateSoundSources(1'000'000, {source});
  EXPECT_EQ(before.AddHeard(2'000'000, {call}, Rigid3d()), 1);
  EXPECT_TRUE(before.people().empty());
  const std::string path = ::testing::TempDir() + "/people_calls_state.yaml";
  before.Save(path);

  PeopleMap after{PeopleMapOptions()};
  ASSERT_TRUE(after.Load(path));
  after.UpdateSoundSources(9'000'000, {source});
  EXPECT_TRUE(after.people().empty());
  EXPECT_EQ(after.AddHeard(10'000'000, {call}, Rigid3d()), 1);
  ASSERT_EQ(after.people().size(), 1u);
  EXPECT_EQ(after.people().begin()->second.sound_source_id, 5);
}

// A restart must remember which sound sources were merged duplicates of a caller. Otherwise each
// later call towards the duplicate makes it a new heard person, which the merge rule folds back
// into the caller in the same update: the map looks the same, but every fold uses up a person id,
// and the next person found is numbered differently from an uninterrupted run.
TEST(PeopleMapTest, AMergedDuplicateSourceStaysMergedAfterARestart) {
  SoundSource first = SourceAt(1, {1.0, 0.0, 0.5}, {0.002, 0.002, 0.01}, true);
  SoundSource second = SourceAt(2, {1.0, 0.4, 0.5}, {0.002, 0.002, 0.01}, true);
  HeardDetection call;
  call.azimuth_sigma_rad = 0.05;
  call.keyword = "help";
  call.confidence = 0.9;
  auto call_towards = [&](PeopleMap* map, const SoundSource& s, int64_t utime) {
    map->UpdateSoundSources(utime - 500'000, {first, second});
    call.azimuth_rad = std::atan2(s.position_m.y(), s.position_m.x());
    const int heard = map->AddHeard(utime, {call}, Rigid3d());
    map->UpdateSoundSources(utime + 500'000, {first, second});
    return heard;
  };
  // The caller's voice split into two sources; calls towards both, then a person seen elsewhere.
  auto first_part = [&](PeopleMap* map) {
    for (int64_t t : {2'000'000, 6'000'000}) call_towards(map, first, t);
    for (int64_t t : {10'000'000, 14'000'000}) call_towards(map, second, t);
  };
  auto second_part = [&](PeopleMap* map) {
    for (int64_t t : {18'000'000, 22'000'000, 26'000'000}) {
      EXPECT_EQ(call_towards(map, second, t), 1);
      ASSERT_EQ(map->people().size(), 1u);
      EXPECT_EQ(map->people().begin()->second.sound_source_id, 1);
    }
    const Rigid2d pose(0.0, 0.0, 0.0);
    map->AddSeen(30'000'000, {PersonAhead(3.0, 2.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
                 pose.translation());
  };
  PeopleMap uninterrupted{PeopleMapOptions()};
  first_part(&uninterrupted);
  second_part(&uninterrupted);

  PeopleMap before{PeopleMapOptions()};
  first_part(&before);
  ASSERT_EQ(before.people().size(), 1u);
  const std::string path = ::testing::TempDir() + "/people_alias_state.yaml";
  before.Save(path);
  PeopleMap after{PeopleMapOptions()};
  ASSERT_TRUE(after.Load(path));
  second_part(&after);

  ASSERT_EQ(uninterrupted.people().size(), 2u);
  ASSERT_EQ(after.people().size(), 2u);
  for (const auto& [id, p] : uninterrupted.people()) {
    ASSERT_EQ(after.people().count(id), 1u)
        << "person " << id << " is numbered differently after the restart";
    EXPECT_EQ(after.people().at(id).num_detections, p.num_detections);
  }
}

TEST(PeopleMapTest, ASeenPersonMovesWithTheSlamNodeItWasSeenFrom) {
  PeopleMap map{PeopleMapOptions()};
  // Seen from node 7 (at the robot's pose then), 3 m ahead; a second person from no node.
  const Rigid2d pose(1.0, 2.0, 0.0);
  const PoseNode node7{7, pose};
  map.AddSeen(1'000'000, {PersonAhead(3.0, 0.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
              pose.translation(), node7);
  map.AddSeen(1'000'000, {PersonAhead(3.0, 3.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
              pose.translation());
  ASSERT_EQ(map.people().size(), 2u);
  EXPECT_EQ(map.AnchorNodeIds(), std::vector<int64_t>{7});
  const Eigen::Vector3d before = map.people().at(1).position_m;
  const Eigen::Vector3d other = map.people().at(2).position_m;
  // A loop closure moves node 7 by 0.5 m and 10 deg: the person stays where the node sees them,
  // node_new * node_old^-1 * before; nodes the map does not hang from change nothing.
  const Rigid2d moved(1.3, 1.6, 10.0 * M_PI / 180);
  EXPECT_EQ(map.MoveWithNodes({{7, moved}, {8, Rigid2d(5, 5, 1)}}), 1);
  const Eigen::Vector2d expected = moved * (pose.inverse() * Eigen::Vector2d(before.head<2>()));
  const Person& p = map.people().at(1);
  EXPECT_NEAR((p.position_m.head<2>() - expected).norm(), 0, 1e-9);
  EXPECT_NEAR(p.position_m.z(), before.z(), 1e-12);
  EXPECT_NEAR((map.people().at(2).position_m - other).norm(), 0, 1e-12);
  // The covariance turns with the node: the long axis (along the camera's view, +x) by 10 deg.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(p.covariance.topLeftCorner<2, 2>());
  const Eigen::Vector2d axis = eig.eigenvectors().col(1);
  EXPECT_NEAR(std::abs(std::atan2(axis.y(), axis.x())), 10.0 * M_PI / 180, 1e-6);
  // The same node reported again does not move the person twice.
  EXPECT_EQ(map.MoveWithNodes({{7, moved}}), 0);
  EXPECT_NEAR((map.people().at(1).position_m.head<2>() - expected).norm(), 0, 1e-9);
  // A detection of the same track after the correction lands in the corrected frame and
  // joins the person there.
  SeenDetection again = PersonAhead(0, 0);
  again.position_camera_m = MapFromCamera(moved).inverse() * p.position_m;
  map.AddSeen(2'000'000, {again}, MapFromCamera(moved), Eigen::Matrix3d::Zero(),
              moved.translation(), PoseNode{9, moved});
  EXPECT_EQ(map.people().at(1).num_detections, 2);
  EXPECT_NEAR((map.people().at(1).position_m.head<2>() - expected).norm(), 0, 1e-6);
  EXPECT_EQ(map.people().at(1).anchor_node_id, 7);  // the first sighting's node stays
}

TEST(PeopleMapTest, AtMostSoManyAnchorNodesConfirmedPeopleFirst) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d pose(0, 0, 0);
  // Three people 2 m apart from nodes 1, 2 and 3; the one of node 1 seen until sure, the one of
  // node 3 seen last.
  for (int k = 0; k < 3; ++k) {
    map.AddSeen(1'000'000 * (k + 1), {PersonAhead(3.0, 2.0 * k)}, MapFromCamera(pose),
                Eigen::Matrix3d::Zero(), pose.translation(), PoseNode{k + 1, pose});
  }
  for (int i = 1; i <= 3; ++i) {
    map.AddSeen(1'000'000 + i * 100'000, {PersonAhead(3.0, 0.0)}, MapFromCamera(pose),
                Eigen::Matrix3d::Zero(), pose.translation(), PoseNode{9, pose});
  }
  ASSERT_EQ(map.people().size(), 3u);
  ASSERT_TRUE(map.people().at(1).confirmed);
  EXPECT_EQ(map.AnchorNodeIds(), (std::vector<int64_t>{1, 2, 3}));
  EXPECT_EQ(map.AnchorNodeIds(2), (std::vector<int64_t>{1, 3}));
  EXPECT_EQ(map.AnchorNodeIds(1), std::vector<int64_t>{1});
}

// Only people the map reports hold a SLAM node: a candidate hangs from the node of its latest
// sighting and is not requested; once reported it keeps that node; once its confidence has
// decayed below reporting it is released again.
TEST(PeopleMapTest, OnlyReportedPeopleHoldSlamNodes) {
  PeopleMapOptions o;
  PeopleMap map{o};
  const Rigid2d pose(0, 0, 0);
  SeenDetection weak = PersonAhead(3.0, 0.0);
  weak.confidence = 0.2;
  auto see = [&](common::Utime t, const SeenDetection& d, int64_t node) {
    map.AddSeen(t, {d}, MapFromCamera(pose), Eigen::Matrix3d::Zero(), pose.translation(),
                PoseNode{node, pose});
  };
  see(1'000'000, weak, 1);
  ASSERT_EQ(map.people().size(), 1u);
  const int id = map.people().begin()->first;
  EXPECT_LT(map.people().at(id).confidence, o.min_report_confidence);
  EXPECT_TRUE(map.AnchorNodeIds(0, 1'000'000).empty());
  EXPECT_EQ(map.AnchorNodeIds(), std::vector<int64_t>{1});  // without a time: every anchor
  see(2'000'000, weak, 2);
  EXPECT_EQ(map.people().at(id).anchor_node_id, 2);  // still a candidate: the latest node
  EXPECT_TRUE(map.AnchorNodeIds(0, 2'000'000).empty());
  see(3'000'000, PersonAhead(3.0, 0.0), 3);  // reported from this sighting on
  ASSERT_GE(map.people().at(id).confidence, o.min_report_confidence);
  ASSERT_FALSE(map.people().at(id).confirmed);
  EXPECT_EQ(map.AnchorNodeIds(0, 3'000'000), std::vector<int64_t>{3});
  see(4'000'000, weak, 4);
  ASSERT_FALSE(map.people().at(id).confirmed);
  EXPECT_EQ(map.people().at(id).anchor_node_id, 3);  // reported: the node stays
  EXPECT_EQ(map.AnchorNodeIds(0, 4'000'000), std::vector<int64_t>{3});
  // Ten half-lives later nobody reports it: released.
  const common::Utime later = 4'000'000 + common::SecondsToUtime(10 * o.confidence_half_life_s);
  EXPECT_TRUE(map.AnchorNodeIds(0, later).empty());
}

TEST(PeopleMapTest, StateSurvivesSaveAndLoadAndCorruptionIsAnError) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d pose(0.5, 0.2, 0.3);
  map.AddSeen(5'000'000, {PersonAhead(2.0, 0.0), PersonAhead(3.0, 1.0)}, MapFromCamera(pose),
              Eigen::Matrix3d::Zero(), pose.translation(), PoseNode{42, Rigid2d(0.4, 0.1, 0.2)});
  for (int i = 1; i <= 3; ++i) {  // the first one seen until sure
    map.AddSeen(5'000'000 + i * 100'000, {PersonAhead(2.0, 0.0)}, MapFromCamera(pose),
                Eigen::Matrix3d::Zero(), pose.translation());
  }
  ASSERT_TRUE(map.people().begin()->second.confirmed);
  ASSERT_FALSE(map.people().rbegin()->second.confirmed);
  const std::string path = ::testing::TempDir() + "/people_state.yaml";
  map.Save(path);
  PeopleMap back{PeopleMapOptions()};
  ASSERT_TRUE(back.Load(path));
  ASSERT_EQ(back.people().size(), 2u);
  for (const auto& [id, p] : map.people()) {
    EXPECT_NEAR((back.people().at(id).position_m - p.position_m).norm(), 0, 1e-9);
    EXPECT_EQ(back.people().at(id).num_detections, p.num_detections);
    EXPECT_EQ(back.people().at(id).confirmed, p.confirmed);
    EXPECT_EQ(back.people().at(id).anchor_node_id, 42);
  }
  // The anchor node's pose came back too: the node reported where it was moves nobody.
  EXPECT_EQ(back.MoveWithNodes({{42, Rigid2d(0.4, 0.1, 0.2)}}), 0);
  EXPECT_EQ(back.MoveWithNodes({{42, Rigid2d(0.5, 0.1, 0.2)}}), 2);
  // New people continue the id sequence.
  back.AddSeen(6'000'000, {PersonAhead(2.0, -3.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
               pose.translation());
  EXPECT_EQ(back.people().rbegin()->first, 3);
  EXPECT_FALSE(back.Load(path + ".missing"));
  std::ofstream(path + ".bad") << "people: [{id: x}]\n";
  EXPECT_THROW(back.Load(path + ".bad"), std::runtime_error);
  EXPECT_EQ(back.people().size(), 3u);  // unchanged by the failed load
}

TEST(PeopleMapTest, FlippedNanAndOtherVersionStateFilesAreRefused) {
  PeopleMap map{PeopleMapOptions()};
  const Rigid2d pose(0.5, 0.2, 0.3);
  map.AddSeen(5'000'000, {PersonAhead(2.0, 0.0)}, MapFromCamera(pose), Eigen::Matrix3d::Zero(),
              pose.translation());
  const std::string path = ::testing::TempDir() + "/people_state_refused.yaml";
  map.Save(path);
  std::string text;
  {
    std::ifstream in(path);
    std::ostringstream all;
    all << in.rdbuf();
    text = all.str();
  }
  const std::string body = text.substr(text.find('\n') + 1);
  PeopleMap back{PeopleMapOptions()};
  const auto refused = [&](const std::string& file_text, const std::string& why) {
    std::ofstream(path, std::ios::trunc) << file_text;
    try {
      back.Load(path);
      ADD_FAILURE() << "loaded: " << why;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_TRUE(back.people().empty());
  };
  // One digit of a position changed: the checksum no longer matches.
  std::string flipped = text;
  const size_t digit = flipped.find_first_of("123456789", flipped.find("position_m"));
  flipped[digit] = flipped[digit] == '9' ? '8' : flipped[digit] + 1;
  refused(flipped, "checksum");
  // A NaN, sealed as the node would have saved it.
  std::string with_nan = body;
  const size_t value = with_nan.find("confidence: ") + 12;
  with_nan.replace(value, with_nan.find('\n', value) - value, ".nan");
  common::WriteSealedState(path, PeopleMap::kStateKind, PeopleMap::kStateVersion, with_nan);
  refused(
      [&] {
        std::ifstream in(path);
        std::ostringstream all;
        all << in.rdbuf();
        return all.str();
      }(),
      "non-finite");
  // Another version, or a body that is not the people map.
  common::WriteSealedState(path + ".v9", PeopleMap::kStateKind, 9, body);
  EXPECT_THROW(back.Load(path + ".v9"), common::StateFileError);
  refused("# sarmap-state people-map v2 bytes 3 crc32 00000000\n[[[", "checksum");
  EXPECT_TRUE(back.people().empty());
}

}  // namespace
}  // namespace people_map
}  // namespace sarmap
