#include "sound_localisation/tracker.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "common/options.h"
#include "sound_localisation/localiser.h"
#include "sound_localisation/test_util.h"

namespace sarmap {
namespace sound {
namespace {

TEST(DoaTracker, BirthDeathPersistenceAndStableIds) {
  const ArrayGeometry g = testing_util::LoadArray("respeaker4");
  TrackerOptions o;
  o.birth_hits = 3;
  o.max_silence_s = 1.0;
  DoaTracker tracker(g, DoaKind::kAzimuthElevation, o);
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, DegToRad(2.0));
  auto meas = [&](double az_deg, double el_deg) {
    TrackMeasurement m;
    m.direction = {DegToRad(az_deg) + noise(rng), DegToRad(el_deg) + noise(rng)};
    m.covariance = Eigen::Matrix2d::Identity() * std::pow(DegToRad(3.0), 2);
    return m;
  };
  std::vector<Track> out;
  double t = 0;
  // Talker A (az 178, across the +-180 wrap) and B (az 60) both speak for 1 s.
  for (int i = 0; i < 8; ++i, t += 0.128)
    out = tracker.Update(t, {meas(178 + (i % 2) * 4, 20), meas(60, 10)});
  ASSERT_EQ(out.size(), 2u);
  const int64_t id_a =
      std::abs(RadToDeg(out[0].direction.azimuth_rad)) > 120 ? out[0].id : out[1].id;
  // A is silent for 0.7 s (kept), B keeps talking.
  for (int i = 0; i < 6; ++i, t += 0.128) out = tracker.Update(t, {meas(60, 10)});
  ASSERT_EQ(out.size(), 2u);
  // A speaks again: same id.
  for (int i = 0; i < 3; ++i, t += 0.128) out = tracker.Update(t, {meas(-179, 20), meas(60, 10)});
  bool found = false;
  for (const auto& tr : out)
    if (std::abs(RadToDeg(WrapAngle(tr.direction.azimuth_rad - M_PI))) < 6) {
      EXPECT_EQ(tr.id, id_a);
      found = true;
    }
  EXPECT_TRUE(found);
  // A single spurious measurement never becomes a track.
  out = tracker.Update(t += 0.128, {meas(-179, 20), meas(60, 10), meas(-60, 40)});
  EXPECT_EQ(out.size(), 2u);
  // Everyone silent for > max_silence_s: all tracks die.
  for (int i = 0; i < 10; ++i, t += 0.128) out = tracker.Update(t, {});
  EXPECT_TRUE(out.empty());
  // A new talker gets a new id.
  for (int i = 0; i < 3; ++i, t += 0.128) out = tracker.Update(t, {meas(-90, 0)});
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id, 2);
}

// Two talkers walk past each other: A from azimuth -50 to +50 deg, B from +50 to -50 deg, over
// 4 s (25 deg/s), elevations 10 and 20 deg; each is detected in 80 % of the 0.128 s blocks with
// 2 deg noise. Scored: after the crossing, does each talker's track (by id) still follow it?
struct CrossingResult {
  int swaps_or_losses = 0;  // trials where a talker's id did not end near it
  int trials = 0;
};

CrossingResult RunCrossing(const TrackerOptions& o) {
  const ArrayGeometry g = testing_util::LoadArray("respeaker4");
  CrossingResult r;
  for (int seed = 1; seed <= 20; ++seed) {
    DoaTracker tracker(g, DoaKind::kAzimuthElevation, o);
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, DegToRad(2.0));
    std::uniform_real_distribution<double> u01(0, 1);
    auto meas = [&](double az_deg, double el_deg) {
      TrackMeasurement m;
      m.direction = {DegToRad(az_deg) + noise(rng), DegToRad(el_deg) + noise(rng)};
      m.covariance = Eigen::Matrix2d::Identity() * std::pow(DegToRad(3.0), 2);
      return m;
    };
    int64_t id_a = -1, id_b = -1;
    std::vector<Track> out;
    const double duration = 4.0, rate = 25.0;
    for (double t = 0; t <= duration; t += 0.128) {
      const double az_a = -50 + rate * t, az_b = 50 - rate * t;
      std::vector<TrackMeasurement> m;
      if (u01(rng) < 0.8) m.push_back(meas(az_a, 10));
      if (u01(rng) < 0.8) m.push_back(meas(az_b, 20));
      out = tracker.Update(t, m);
      if (t < 1.0)  // before the crossing (at 2 s): name the tracks
        for (const auto& tr : out) {
          if (std::abs(RadToDeg(WrapAngle(tr.direction.azimuth_rad - DegToRad(az_a)))) < 8)
            id_a = tr.id;
          if (std::abs(RadToDeg(WrapAngle(tr.direction.azimuth_rad - DegToRad(az_b)))) < 8)
            id_b = tr.id;
        }
    }
    auto ends_near = [&](int64_t id, double az_deg) {
      for (const auto& tr : tracker.tracks())
        if (tr.id == id)
          return std::abs(RadToDeg(WrapAngle(tr.direction.azimuth_rad - DegToRad(az_deg)))) < 10;
      return false;
    };
    ++r.trials;
    const double t_end = std::floor(duration / 0.128) * 0.128;
    if (id_a < 0 || id_b < 0 || id_a == id_b || !ends_near(id_a, -50 + rate * t_end) ||
        !ends_near(id_b, 50 - rate * t_end))
      ++r.swaps_or_losses;
  }
  return r;
}

// A linear array measures one angle; the tracker's second angle is never observed. Its
// variance must stay what the measurements say ("unknown"), not grow with every update until
// it turns negative and the track's direction becomes NaN (a minute of a talker at 8 Hz).
TEST(DoaTracker, OneAngleKindsStayFiniteOverALongTrack) {
  const ArrayGeometry g = testing_util::LoadArray("respeaker4");
  for (const DoaKind kind : {DoaKind::kAngle1d, DoaKind::kAzimuth}) {
    for (const double velocity_noise : {0.0, 5.0}) {
      TrackerOptions o;
      o.velocity_noise_deg_per_s_sqrt_s = velocity_noise;
      DoaTracker tracker(g, kind, o);
      std::mt19937 rng(3);
      std::normal_distribution<double> noise(0.0, DegToRad(2.0));
      std::vector<Track> out;
      for (int i = 0; i < 480; ++i) {
        TrackMeasurement m;
        m.direction = {DegToRad(70.0) + noise(rng), 0.0};
        m.covariance << std::pow(DegToRad(3.0), 2), 0, 0, M_PI * M_PI;  // second angle unknown
        out = tracker.Update(i * 0.128, {m});
        for (const Track& t : out) {
          ASSERT_TRUE(std::isfinite(t.direction.azimuth_rad)) << "update " << i;
          ASSERT_TRUE(t.covariance.allFinite()) << "update " << i;
          ASSERT_GT(t.covariance(0, 0), 0) << "update " << i;
          ASSERT_GE(t.covariance(1, 1), 0) << "update " << i;
        }
      }
      ASSERT_EQ(out.size(), 1u);
      // The random-walk model follows the last few DOAs (2 deg noise each).
      EXPECT_NEAR(RadToDeg(out[0].direction.azimuth_rad), 70.0, 5.0);
      EXPECT_LT(std::sqrt(out[0].covariance(0, 0)), DegToRad(3.0));  // better than one DOA
      EXPECT_DOUBLE_EQ(out[0].direction.elevation_rad, 0.0);
    }
  }
}

TEST(DoaTracker, KeepsTwoCrossingTalkersApart) {
  TrackerOptions random_walk;
  // The shipped tracker (bearing rates).
  const TrackerOptions constant_velocity =
      common::LoadOptions<LocaliserOptions>(
          std::string(SARMAP_SOURCE_DIR) + "/config/sound_localisation.yaml", {}, "localiser")
          .tracker;
  ASSERT_GT(constant_velocity.velocity_noise_deg_per_s_sqrt_s, 0);
  const CrossingResult rw = RunCrossing(random_walk), cv = RunCrossing(constant_velocity);
  std::printf(
      "crossing talkers, ids swapped or lost: random walk %d / %d, constant velocity %d / %d\n",
      rw.swaps_or_losses, rw.trials, cv.swaps_or_losses, cv.trials);
  EXPECT_LE(cv.swaps_or_losses, 1);
  EXPECT_LT(cv.swaps_or_losses, rw.swaps_or_losses);
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
