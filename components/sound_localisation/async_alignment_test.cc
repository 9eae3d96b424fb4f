#include "sound_localisation/async_alignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sound_localisation/localiser.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/room_simulation.h"

namespace sarmap {
namespace sound {
namespace {

using testing_util::LoadArray;
using testing_util::WhiteNoise;

// Mean absolute azimuth error (deg) of the per-block SRP-PHAT estimates after `skip_samples`.
double MeanAzimuthError(const ArrayGeometry& g, const std::vector<std::vector<float>>& mics, double az_rad,
                        int64_t skip_samples, size_t* blocks) {
  LocaliserOptions o;
  o.method = "srp_phat";
  o.max_sources = 1;
  Localiser loc(g, o, nullptr);
  std::vector<LocaliserOutput> outs;
  loc.PushFloat(mics, 0, mics[0].size(), &outs);
  double sum = 0;
  *blocks = 0;
  for (const auto& out : outs) {
    if (out.directions.empty() || out.end_sample < skip_samples) continue;
    sum += std::abs(RadToDeg(WrapAngle(out.directions[0].direction.azimuth_rad - az_rad)));
    ++*blocks;
  }
  return *blocks ? sum / *blocks : 999;
}

TEST(AsyncStreamAligner, ZeroOffsetsPassSignalsThrough) {
  const std::vector<float> x = WhiteNoise(2000, 1);
  AsyncStreamAligner a(16000, {}, {}, 1, 16);
  a.Push(0, 0, x.data(), 1000);
  a.Push(0, 1000, x.data() + 1000, 1000);
  std::vector<std::vector<float>> out;
  const size_t n = a.Pull(&out);
  ASSERT_EQ(n, 2000u - 16);
  for (size_t i = 0; i < n; ++i) ASSERT_NEAR(out[0][i], x[i], 1e-5);
}

TEST(AsyncStreamAligner, DropoutsReadAsZerosAndAreCounted) {
  const std::vector<float> x(100, 1.0f);
  AsyncStreamAligner a(16000, {}, {}, 1, 4);
  a.Push(0, 0, x.data(), 100);
  a.Push(0, 150, x.data(), 100);  // 50 samples lost
  EXPECT_EQ(a.dropped_samples(), 50);
  std::vector<std::vector<float>> out;
  a.Pull(&out);
  EXPECT_NEAR(out[0][125], 0.0f, 1e-6);
  EXPECT_NEAR(out[0][50], 1.0f, 1e-6);
  EXPECT_THROW(AsyncStreamAligner(16000, {0.0, 0.1}, {}, 3), std::invalid_argument);
}

// A ReSpeaker-shaped array whose four microphones sit on four cards with injected start
// offsets (up to 2.1 ms, ~10x the array's largest TDOA) and clock drifts (up to 120 ppm):
// after alignment SRP-PHAT is as accurate as with the synchronous recording (within 1 deg).
TEST(AsyncStreamAligner, RestoresDoaAccuracyOfAnAsynchronousArray) {
  const ArrayGeometry g = LoadArray("respeaker4");
  Room room;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  const double az = DegToRad(47.3), el = DegToRad(20);
  const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const int fs = 16000;
  const size_t lead = fs, n = 3 * fs;  // 1 s of room noise (the activity gate learns its floor), then the source
  std::vector<float> source = WhiteNoise(n, 2);
  std::fill(source.begin(), source.begin() + lead, 0.0f);
  const auto sync =
      SimulateRoom(room, g.positions_m.colwise() + centre, {{centre + 1.5 * u, source}}, n, 0.001, 3);
  const std::vector<double> tau_s = {0.0, 0.0013, -0.0007, 0.0021};
  const std::vector<double> delta = {0.0, 80e-6, -120e-6, 50e-6};
  std::vector<std::vector<float>> async(4);
  for (int m = 0; m < 4; ++m) async[m] = RecordAsynchronously(sync[m], tau_s[m], delta[m], fs);  // room_simulation.h

  // Each card delivers its own blocks with its own counter.
  AsyncStreamAligner aligner(fs, tau_s, delta, 4);
  std::vector<std::vector<float>> aligned(4);
  for (size_t s = 0; s < n; s += 512)
    for (int m = 0; m < 4; ++m) {
      aligner.Push(m, static_cast<int64_t>(s), async[m].data() + s, std::min<size_t>(512, n - s));
      aligner.Pull(&aligned);
    }
  ASSERT_GT(aligned[0].size(), n - 200);
  for (auto& a : aligned) a.resize(aligned[0].size());

  const int64_t skip = static_cast<int64_t>(lead) + fs / 2;
  size_t b_sync = 0, b_async = 0, b_aligned = 0;
  const double e_sync = MeanAzimuthError(g, sync, az, skip, &b_sync);
  const double e_async = MeanAzimuthError(g, async, az, skip, &b_async);
  const double e_aligned = MeanAzimuthError(g, aligned, az, skip, &b_aligned);
  std::printf("asynchronous respeaker4 (tau up to 2.1 ms, drift up to 120 ppm), SRP-PHAT mean azimuth error: "
              "synchronous %.2f deg (%zu blocks), unaligned %.2f deg (%zu; 999 = no confident direction), aligned %.2f deg "
              "(%zu)\n",
              e_sync, b_sync, e_async, b_async, e_aligned, b_aligned);
  ASSERT_GT(b_aligned, 10u);
  EXPECT_LE(e_aligned, e_sync + 1.0);
  // The injected offsets do matter: without alignment there is no confident direction, or a wrong one.
  EXPECT_TRUE(b_async == 0 || e_async > e_sync + 5.0) << e_async;
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
