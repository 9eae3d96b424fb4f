// sarmap-sound-map's input handling without the bus: POSE and DOA in time order into the map,
// an anchor request when a source is born, SOUND_MAP every publish_period_s, late inputs dropped.
#include "sound_map/sound_map_intake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace sarmap {
namespace sound_map {
namespace {

sarmap::pose_t Pose(int64_t utime, double x_m, int64_t node_id) {
  sarmap::pose_t m{};
  m.header.utime = utime;
  m.position_m[0] = x_m;
  m.orientation[0] = 1;
  for (int i = 0; i < 6; ++i) m.covariance[7 * i] = 1e-4;
  m.node_id = node_id;
  return m;
}

sarmap::doa_t Doa(int64_t utime, double azimuth_rad) {
  sarmap::doa_t m{};
  m.header.utime = utime;
  m.device_id = "mic";
  sarmap::doa_source_t s{};
  s.track_id = 1;
  s.kind = OnlineSoundMap::kAzimuth;
  s.azimuth_rad = azimuth_rad;
  s.covariance[0] = s.covariance[3] = std::pow(2 * M_PI / 180, 2);
  m.sources.push_back(s);
  m.num_sources = 1;
  return m;
}

TEST(SoundMapIntakeTest, DriftingPastASourcePlacesItAndPublishes) {
  SoundMapNodeOptions options;
  OnlineSoundMap map(options.map, ArrayMount{});
  std::vector<sarmap::sound_map_t> published;
  int requests = 0;
  SoundMapIntake intake(
      options, &map, [&](sarmap::sound_map_t& m) { published.push_back(m); },
      [&](sarmap::slam_anchor_request_t&) { ++requests; });
  const Eigen::Vector2d source(3.0, 2.0);
  // The robot drives along x at 0.3 m/s for 20 s; a DOA towards the source every 0.1 s.
  for (int k = 0; k <= 200; ++k) {
    const int64_t utime = 1'000'000 + k * 100'000;
    const double x = 0.03 * k;
    intake.OnPose(Pose(utime, x, k / 10));
    intake.OnDoa(Doa(utime + 50'000, std::atan2(source.y(), source.x() - x)));
  }
  intake.Finish();
  EXPECT_GE(requests, 1);
  ASSERT_GE(published.size(), 10u);  // every 0.5 s of message time, and the last one
  for (size_t i = 1; i < published.size(); ++i)
    EXPECT_GE(published[i].header.utime, published[i - 1].header.utime);
  const sarmap::sound_map_t& last = published.back();
  ASSERT_EQ(last.num_sources, 1);
  const auto& s = last.sources[0];
  ASSERT_TRUE(s.has_position);
  EXPECT_NEAR(s.position_m[0], source.x(), 0.3);
  EXPECT_NEAR(s.position_m[1], source.y(), 0.3);
  // An input older than what was already applied is late: dropped and counted.
  intake.OnDoa(Doa(1'000'000, 0.0));
  EXPECT_EQ(intake.dropped_late(), 1);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
