// SoundLocalisationNode in-process over memq://: white noise from one direction as AUDIO blocks
// on the bus gives DOA and DOA_MAP towards it; blocks of the wrong format or repeated are
// dropped and counted while the stream goes on.
#include "sound_localisation/sound_localisation_node.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/options.h"
#include "common/time.h"
#include "sound_localisation/test_util.h"

namespace sarmap {
namespace sound {
namespace {

struct Bus {
  common::Node node{"sound_localisation_node_test", "memq://"};
  std::vector<doa_t> doa, map_doa;
  common::Node::Publisher<audio_frame_t> audio = node.Advertise<audio_frame_t>("AUDIO");
  Bus() {
    node.Subscribe<doa_t>("DOA", [this](const doa_t& m, const auto&) { doa.push_back(m); });
    node.Subscribe<doa_t>("DOA_MAP", [this](const doa_t& m, const auto&) { map_doa.push_back(m); });
  }
  void Send(audio_frame_t m) {
    audio.Publish(&m);
    for (int i = 0; i < 3; ++i) node.SpinOnce(0.001);
  }
};

SoundLocalisationOptions NodeOptions() {
  const std::string root = SARMAP_SOURCE_DIR;
  auto options =
      common::LoadOptions<SoundLocalisationOptions>(root + "/config/sound_localisation.yaml", {});
  options.array = root + "/" + options.array;
  return options;
}

// Block `k` of 512 samples of `mics` as the device sends it (interleaved int16, channel map).
audio_frame_t Block(const ArrayGeometry& g, const std::vector<std::vector<float>>& mics, int k,
                    int64_t start_utime) {
  int channels = 0;
  for (int c : g.channel_map) channels = std::max(channels, c + 1);
  const int n = 512;
  audio_frame_t m{};
  m.header.utime =
      start_utime + common::SecondsToUtime(static_cast<double>(k) * n / g.sample_rate_hz);
  m.header.frame = "mic_array";
  m.device_id = "respeaker";
  m.sample_rate_hz = g.sample_rate_hz;
  m.num_channels = channels;
  m.num_samples = n;
  m.first_sample_index = static_cast<int64_t>(k) * n;
  m.sample_format = audio_frame_t::SAMPLE_INT16;
  m.num_values = channels * n;
  m.samples.assign(m.num_values, 0);
  for (int mic = 0; mic < g.num_mics(); ++mic)
    for (int i = 0; i < n; ++i)
      m.samples[static_cast<size_t>(i) * channels + g.channel_map[mic]] = static_cast<int16_t>(
          std::lround(std::clamp(mics[mic][static_cast<size_t>(k) * n + i], -1.0f, 1.0f) * 32767));
  return m;
}

TEST(SoundLocalisationNodeTest, NoiseFromOneDirectionOnTheBusGivesDoasTowardsIt) {
  Bus bus;
  const SoundLocalisationOptions options = NodeOptions();
  SoundLocalisationNode adapter(options, &bus.node);
  const ArrayGeometry g = ArrayGeometry::FromOptions(common::LoadMicArray(options.array));
  const double fs = g.sample_rate_hz, azimuth = DegToRad(-70);
  const size_t n = static_cast<size_t>(3.0 * fs);
  const std::vector<float> s = testing_util::WhiteNoise(n, 5);
  const Eigen::VectorXd delays = g.Delays(Eigen::Vector3d(std::cos(azimuth), std::sin(azimuth), 0));
  std::vector<std::vector<float>> mics(g.num_mics(), std::vector<float>(n, 0.0f));
  for (int m = 0; m < g.num_mics(); ++m)
    testing_util::AddDelayed(s, 40 + delays[m] * fs, 0.2, &mics[m]);

  const int64_t start_utime = 1'700'000'000'000'000;
  const int blocks = static_cast<int>(n / 512);
  for (int k = 0; k < blocks; ++k) {
    bus.Send(Block(g, mics, k, start_utime));
    if (k == blocks / 2) {
      audio_frame_t wrong_rate = Block(g, mics, k + 1, start_utime);
      wrong_rate.sample_rate_hz = 48000;
      bus.Send(wrong_rate);
      audio_frame_t too_few = Block(g, mics, k + 1, start_utime);
      too_few.num_channels = 2;
      too_few.num_values = 2 * too_few.num_samples;
      too_few.samples.resize(too_few.num_values);
      bus.Send(too_few);
      bus.Send(Block(g, mics, k, start_utime));  // a repeat
    }
  }
  EXPECT_EQ(adapter.dropped(), 3);
  ASSERT_GE(bus.doa.size(), 10u);
  ASSERT_GE(bus.map_doa.size(), 10u);
  int towards = 0, total = 0;
  for (const auto& m : bus.doa) {
    EXPECT_GE(m.header.utime, start_utime);
    for (const auto& src : m.sources) {
      ++total;
      towards += std::abs(std::remainder(src.azimuth_rad - azimuth, 2 * M_PI)) < DegToRad(5);
    }
  }
  EXPECT_GE(towards, total * 8 / 10) << towards << " of " << total << " within 5 deg";
  EXPECT_EQ(adapter.published(), static_cast<int64_t>(bus.doa.size() + bus.map_doa.size()));
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
