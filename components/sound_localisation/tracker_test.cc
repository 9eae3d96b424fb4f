#include "sound_localisation/tracker.h"

#include <gtest/gtest.h>

#include <random>

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
  for (int i = 0; i < 8; ++i, t += 0.128) out = tracker.Update(t, {meas(178 + (i % 2) * 4, 20), meas(60, 10)});
  ASSERT_EQ(out.size(), 2u);
  const int64_t id_a = std::abs(RadToDeg(out[0].direction.azimuth_rad)) > 120 ? out[0].id : out[1].id;
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

}  // namespace
}  // namespace sound
}  // namespace sarmap
