#include "sound_map/bearing_evidence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

#include "sound_map/online_sound_map.h"

namespace sarmap {
namespace sound_map {
namespace {

double Bearing(const Pose2& p, const Eigen::Vector2d& s) {
  return WrapAngle(std::atan2(s.y() - p.y, s.x() - p.x) - p.yaw);
}

// A robot drives 4 m along x and 2 m along y; each source is heard in short calls (2 s in 8 s,
// at 4 DOAs a second), with 3 deg of noise and 10 % of the DOAs anywhere (reflections).
struct Calls {
  std::vector<Eigen::Vector2d> sources{{3.0, 2.5}, {5.0, -2.0}};
  std::vector<int> classes{OnlineSoundMap::kClassVoice, OnlineSoundMap::kClassMachinery};
  std::vector<BearingEvidence::Ray> rays;
  explicit Calls(int64_t node = -1) {
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 3 * M_PI / 180);
    std::uniform_real_distribution<double> any(-M_PI, M_PI), u(0, 1);
    for (int k = 0; k < 240; ++k) {  // 0.25 s apart, 60 s, 0.1 m/s
      const double t = 0.25 * k;
      const Pose2 pose(std::min(0.025 * k, 4.0), std::max(0.0, 0.025 * k - 4.0),
                       k < 160 ? 0.0 : M_PI / 2);
      for (size_t j = 0; j < sources.size(); ++j) {
        if (std::fmod(t + 4.0 * j, 8.0) >= 2.0) continue;  // calling 2 s in 8
        BearingEvidence::Ray r;
        r.utime = static_cast<int64_t>(t * 1e6);
        r.node = node;
        r.node_from_base = pose;
        r.azimuth_rad =
            u(rng) < 0.1 ? any(rng) : WrapAngle(Bearing(pose, sources[j]) + noise(rng));
        r.sigma_rad = 3 * M_PI / 180;
        r.sound_class = classes[j];
        rays.push_back(r);
      }
    }
  }
};

TEST(BearingEvidence, IntermittentCallsAreTriangulated) {
  Calls calls;
  BearingEvidence evidence(BearingEvidenceOptions{}, ArrayMount{});
  for (const auto& r : calls.rays) evidence.Add(r);
  const auto found = evidence.Solve({}, nullptr, nullptr);
  ASSERT_EQ(found.size(), 2u);
  for (size_t j = 0; j < calls.sources.size(); ++j) {
    const BearingEvidence::Source* nearest = nullptr;
    for (const auto& s : found)
      if (!nearest || (s.position_m - calls.sources[j]).norm() <
                          (nearest->position_m - calls.sources[j]).norm())
        nearest = &s;
    EXPECT_LT((nearest->position_m - calls.sources[j]).norm(), 0.25) << "source " << j;
    EXPECT_LT(nearest->largest_sigma_m, 0.3);
    // Its class: the votes of the rays it explains.
    int best = 0;
    for (int c = 1; c < 5; ++c)
      if (nearest->class_votes[c] > nearest->class_votes[best]) best = c;
    EXPECT_EQ(best, calls.classes[j]);
  }
}

// A source's class is voted by the rays it explains (responsibility >= 0.5), as its support and
// its covariance are: another source's rays that pass near it, mostly explained there, do not
// dilute it (a caller beside a machine stays a voice).
TEST(BearingEvidence, OnlyTheRaysASourceExplainsVoteForItsClass) {
  Calls calls;
  // The machine sounds without pause, heard from every pose, its bearing passing 0.4 m from the
  // caller at the start of the drive.
  calls.sources[1] = Eigen::Vector2d(3.0, 4.5);
  std::vector<BearingEvidence::Ray> machine;
  for (int k = 0; k < 240; ++k) {
    const double t = 0.25 * k;
    const Pose2 pose(std::min(0.025 * k, 4.0), std::max(0.0, 0.025 * k - 4.0),
                     k < 160 ? 0.0 : M_PI / 2);
    BearingEvidence::Ray r;
    r.utime = static_cast<int64_t>(t * 1e6);
    r.node_from_base = pose;
    r.azimuth_rad = Bearing(pose, calls.sources[1]);
    r.sigma_rad = 3 * M_PI / 180;
    r.sound_class = OnlineSoundMap::kClassMachinery;
    machine.push_back(r);
  }
  BearingEvidence evidence(BearingEvidenceOptions{}, ArrayMount{});
  for (const auto& r : calls.rays)
    if (r.sound_class == OnlineSoundMap::kClassVoice) evidence.Add(r);
  for (const auto& r : machine) evidence.Add(r);
  const auto found = evidence.Solve({}, nullptr, nullptr);
  const BearingEvidence::Source* caller = nullptr;
  for (const auto& s : found)
    if ((s.position_m - calls.sources[0]).norm() < 0.3) caller = &s;
  ASSERT_NE(caller, nullptr);
  const auto& v = caller->class_votes;
  const double share = v[OnlineSoundMap::kClassVoice] / (v[1] + v[2] + v[3] + v[4]);
  EXPECT_GT(share, 0.97) << "machinery votes " << v[OnlineSoundMap::kClassMachinery];
}

TEST(BearingEvidence, BearingsFromOnePlaceGiveNoPosition) {
  // 40 DOAs towards (3, 2) from the origin: a line, no crossing.
  BearingEvidence evidence(BearingEvidenceOptions{}, ArrayMount{});
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 2 * M_PI / 180);
  for (int k = 0; k < 40; ++k) {
    BearingEvidence::Ray r;
    r.utime = k * 250000;
    r.azimuth_rad = std::atan2(2.0, 3.0) + noise(rng);
    r.sigma_rad = 2 * M_PI / 180;
    evidence.Add(r);
  }
  for (const auto& s : evidence.Solve({}, nullptr, nullptr)) EXPECT_GT(s.largest_sigma_m, 2.0);
}

TEST(BearingEvidence, RaysMoveWithTheirNode) {
  // Every ray heard from node 7: moving the node 1 m along y moves the sources 1 m.
  Calls calls(7);
  BearingEvidence evidence(BearingEvidenceOptions{}, ArrayMount{});
  for (const auto& r : calls.rays) evidence.Add(r);
  EXPECT_TRUE(evidence.Solve({}, nullptr, nullptr).empty());  // the node is unknown
  const auto before = evidence.Solve({{7, Pose2(0, 0, 0)}}, nullptr, nullptr);
  const auto after = evidence.Solve({{7, Pose2(0, 1, 0)}}, nullptr, nullptr);
  ASSERT_EQ(before.size(), 2u);
  ASSERT_EQ(after.size(), 2u);
  for (size_t k = 0; k < 2; ++k)
    EXPECT_LT((after[k].position_m - before[k].position_m - Eigen::Vector2d(0, 1)).norm(), 0.05);
}

TEST(BearingEvidence, HeardDirectionsMarkTheSourceTheyPointAt) {
  Calls calls;
  BearingEvidence evidence(BearingEvidenceOptions{}, ArrayMount{});
  for (const auto& r : calls.rays) evidence.Add(r);
  BearingEvidence::Ray heard;
  heard.utime = 1000000;
  heard.node_from_base = Pose2(1.0, 0.0, 0.0);
  heard.azimuth_rad = Bearing(heard.node_from_base, calls.sources[0]);
  heard.sigma_rad = 5 * M_PI / 180;
  heard.heard = heard.called = true;
  evidence.Add(heard);
  const auto found = evidence.Solve({}, nullptr, nullptr);
  ASSERT_EQ(found.size(), 2u);
  for (const auto& s : found) {
    const bool first = (s.position_m - calls.sources[0]).norm() < 0.5;
    EXPECT_EQ(s.heard, first);
    EXPECT_EQ(s.called, first);
  }
}

TEST(BearingEvidence, OutsideTheSiteNothingIsFound) {
  Calls calls;
  BearingEvidence evidence(BearingEvidenceOptions{}, ArrayMount{});
  for (const auto& r : calls.rays) evidence.Add(r);
  // The site ends at y = 1: only the source at (5, -2) is inside, and the other is not drawn
  // onto the site's edge.
  const Eigen::Vector2d lo(-2, -5), hi(8, 1);
  const auto found = evidence.Solve({}, &lo, &hi);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_LT((found[0].position_m - calls.sources[1]).norm(), 0.25);
}

TEST(BearingEvidence, SaveAndLoadGiveTheSameSources) {
  Calls calls;
  BearingEvidence a(BearingEvidenceOptions{}, ArrayMount{}),
      b(BearingEvidenceOptions{}, ArrayMount{});
  for (const auto& r : calls.rays) a.Add(r);
  std::ostringstream out(std::ios::binary);
  common::BinaryWriter writer(&out);
  a.Save(&writer);
  std::istringstream in(out.str(), std::ios::binary);
  common::BinaryReader reader(&in, "test");
  b.Load(&reader);
  EXPECT_EQ(b.size(), a.size());
  const auto sa = a.Solve({}, nullptr, nullptr), sb = b.Solve({}, nullptr, nullptr);
  ASSERT_EQ(sa.size(), sb.size());
  for (size_t k = 0; k < sa.size(); ++k)
    EXPECT_LT((sa[k].position_m - sb[k].position_m).norm(), 1e-9);
}

TEST(BearingEvidence, ASourceHeardLongAgoSurvivesTheRayLimit) {
  // The calls of Calls (both sources), then 3000 DOAs of a third source only, solved every 40
  // rays as the node does; at most 500 rays are kept: rays from one place in one direction
  // are merged, and the old calls still place the first two sources.
  BearingEvidenceOptions options;
  options.max_rays = 500;
  BearingEvidence evidence(options, ArrayMount{});
  Calls calls;
  for (const auto& r : calls.rays) evidence.Add(r);
  const Eigen::Vector2d third(1.0, -3.0);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 3 * M_PI / 180);
  for (int k = 0; k < 3000; ++k) {
    BearingEvidence::Ray r;
    r.utime = 60000000 + k * 250000;
    r.node_from_base = Pose2(4.0 - 4.0 * (k % 400) / 400.0, 2.0, M_PI);
    r.azimuth_rad = WrapAngle(Bearing(r.node_from_base, third) + noise(rng));
    r.sigma_rad = 3 * M_PI / 180;
    evidence.Add(r);
    if (k % 40 == 0) evidence.Solve({}, nullptr, nullptr);
  }
  EXPECT_LE(evidence.size(), 500u);
  const auto found = evidence.Solve({}, nullptr, nullptr);
  ASSERT_EQ(found.size(), 3u);
  double worth = 0;
  for (const auto& s : found) worth += s.rays;
  EXPECT_GT(worth, 0.7 * (calls.rays.size() + 3000));  // the kept rays stand for all (less clutter)
  for (const Eigen::Vector2d& truth : {calls.sources[0], calls.sources[1], third}) {
    double nearest = INFINITY;
    for (const auto& s : found) nearest = std::min(nearest, (s.position_m - truth).norm());
    EXPECT_LT(nearest, 0.3);
  }
  BearingEvidence::Ray bad;
  bad.sigma_rad = 0.05;
  bad.azimuth_rad = NAN;  // a non-finite DOA is not kept
  const size_t n = evidence.size();
  evidence.Add(bad);
  EXPECT_EQ(evidence.size(), n);
}

// In the sound map: a caller heard in short calls while the robot turns fast (the EKF drops
// those DOAs) is placed where the bearings cross, and is a person when heard calling.
TEST(BearingEvidence, TheSoundMapPlacesACallerHeardWhileTurning) {
  const Eigen::Vector2d caller(3.0, 2.0);
  // Drive 5 m along x at 0.25 m/s, turning on the spot (30 deg/s) after every metre, 10 Hz
  // poses; the calls come only while the robot turns, 5 DOAs a second, each with the heading
  // of 0.3 s earlier (the localiser's lag).
  std::vector<Pose2> poses;
  for (int leg = 0; leg < 5; ++leg) {
    for (int k = 0; k < 40; ++k) poses.emplace_back(leg + 0.025 * k, 0.0, 0.0);
    for (int k = 0; k < 24; ++k) poses.emplace_back(leg + 1.0, 0.0, WrapAngle(k * M_PI / 60));
  }
  const auto run = [&](bool evidence, int64_t* dropped) {
    OnlineSoundMapOptions options;
    options.evidence.enabled = evidence;
    OnlineSoundMap map(options, ArrayMount{});
    std::mt19937 rng(9);
    std::normal_distribution<double> noise(0.0, 3 * M_PI / 180);
    int64_t t = 0;
    for (size_t k = 0; k < poses.size(); ++k, t += 100000) {
      map.OnPose(t, ToRigid2d(poses[k]), Eigen::Matrix3d::Identity() * 1e-6,
                 static_cast<int64_t>(k));
      if ((k % 64) < 40 || k % 2) continue;
      OnlineSoundMap::Doa d;
      d.azimuth_rad = WrapAngle(Bearing(poses[k - 3], caller) + noise(rng));
      d.covariance = Eigen::Matrix2d::Identity() * std::pow(3 * M_PI / 180, 2);
      d.sound_class = OnlineSoundMap::kClassVoice;
      map.OnDoa(t, "respeaker", {d});
      if (k % 8 == 0) {
        d.called = true;
        map.OnHeardDirection(d);
      }
    }
    *dropped = map.counters().doa_while_turning;
    std::vector<OnlineSoundMap::Source> people;
    for (const auto& s : map.Sources(t))
      if (s.is_person) people.push_back(s);
    return people;
  };
  int64_t dropped = 0;
  const auto with = run(true, &dropped);
  EXPECT_GT(dropped, 0);
  ASSERT_EQ(with.size(), 1u);
  EXPECT_LT((with[0].position_m.head<2>() - caller).norm(), 0.3);
  EXPECT_EQ(with[0].priority, OnlineSoundMap::kPriorityCall);
  EXPECT_TRUE(run(false, &dropped).empty());  // the EKF alone never hears the caller
}

// A caller heard all along (the EKF places her too): one placed source for her, whichever of
// the two maps places her better.
TEST(BearingEvidence, OneSourcePerCallerWithTheEkf) {
  const Eigen::Vector2d caller(3.0, 2.0);
  OnlineSoundMap map(OnlineSoundMapOptions{}, ArrayMount{});
  std::mt19937 rng(13);
  std::normal_distribution<double> noise(0.0, 3 * M_PI / 180);
  int64_t t = 0;
  for (int k = 0; k < 300; ++k, t += 100000) {  // 7.5 m along x at 0.25 m/s
    const Pose2 pose(0.025 * k, 0.0, 0.0);
    map.OnPose(t, ToRigid2d(pose), Eigen::Matrix3d::Identity() * 1e-6, k);
    if (k % 2) continue;
    OnlineSoundMap::Doa d;
    d.track_id = 1;
    d.azimuth_rad = WrapAngle(Bearing(pose, caller) + noise(rng));
    d.covariance = Eigen::Matrix2d::Identity() * std::pow(3 * M_PI / 180, 2);
    d.sound_class = OnlineSoundMap::kClassVoice;
    map.OnDoa(t, "respeaker", {d});
  }
  ASSERT_FALSE(map.evidence_sources().empty());
  int near = 0;
  for (const auto& s : map.Sources(t))
    if (s.has_position && (s.position_m.head<2>() - caller).norm() < 1.0) ++near;
  EXPECT_EQ(near, 1);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
