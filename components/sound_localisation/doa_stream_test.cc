// sarmap-sound-localisation's audio -> DOA messages without the bus: white noise from one
// direction through the node's configuration (config/sound_localisation.yaml) gives DOA and
// DOA_MAP messages pointing at it, stamped on the block's clock.
#include "sound_localisation/doa_stream.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/time.h"
#include "sound_localisation/test_util.h"

namespace sarmap {
namespace sound {
namespace {

TEST(DoaStreamTest, NoiseFromOneDirectionGivesDoasTowardsIt) {
  const std::string root = SARMAP_SOURCE_DIR;
  const auto options =
      common::LoadOptions<SoundLocalisationOptions>(root + "/config/sound_localisation.yaml", {});
  const auto array = common::LoadMicArray(root + "/" + options.array);
  DoaStream stream(options, array, root + "/config/arrays/");
  ASSERT_TRUE(stream.has_map_stream());
  const ArrayGeometry& g = stream.geometry();
  const double fs = g.sample_rate_hz, azimuth = DegToRad(40);
  const size_t n = static_cast<size_t>(3.0 * fs);
  const std::vector<float> s = testing_util::WhiteNoise(n, 3);
  const Eigen::VectorXd delays = g.Delays(Eigen::Vector3d(std::cos(azimuth), std::sin(azimuth), 0));
  std::vector<std::vector<float>> mics(g.num_mics(), std::vector<float>(n, 0.0f));
  for (int m = 0; m < g.num_mics(); ++m)
    testing_util::AddDelayed(s, 40 + delays[m] * fs, 0.2, &mics[m]);
  // Interleaved int16 blocks of 512 samples through the array's channel map.
  int channels = 0;
  for (int c : g.channel_map) channels = std::max(channels, c + 1);
  const int block = 512;
  const int64_t start_utime = 1'000'000'000;
  std::vector<sarmap::doa_t> doa, map_doa;
  for (size_t first = 0; first + block <= n; first += block) {
    std::vector<int16_t> data(static_cast<size_t>(block) * channels, 0);
    for (int m = 0; m < g.num_mics(); ++m)
      for (int i = 0; i < block; ++i)
        data[static_cast<size_t>(i) * channels + g.channel_map[m]] =
            static_cast<int16_t>(std::lround(std::clamp(mics[m][first + i], -1.0f, 1.0f) * 32767));
    stream.Push(data.data(), block, channels, start_utime + common::SecondsToUtime(first / fs),
                &doa, &map_doa);
  }
  ASSERT_GE(doa.size(), 10u);
  ASSERT_GE(map_doa.size(), 10u);
  int towards = 0, total = 0;
  int64_t last_utime = 0;
  for (const auto& m : doa) {
    EXPECT_GE(m.header.utime, start_utime);
    EXPECT_LE(m.header.utime, start_utime + common::SecondsToUtime(3.0));
    EXPECT_GE(m.header.utime, last_utime);
    last_utime = m.header.utime;
    for (const auto& src : m.sources) {
      ++total;
      towards += std::abs(std::remainder(src.azimuth_rad - azimuth, 2 * M_PI)) < DegToRad(5);
      EXPECT_EQ(src.method, static_cast<int8_t>(sarmap::doa_source_t::METHOD_SRP_PHAT));
    }
  }
  EXPECT_GE(towards, total * 8 / 10) << towards << " of " << total << " within 5 deg";
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
