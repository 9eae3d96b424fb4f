// sarmap-sound-localisation's audio -> DOA messages without the bus: white noise from one
// direction through the node's configuration (config/sound_localisation.yaml) gives DOA and
// DOA_MAP messages pointing at it, stamped on the block's clock.
#include "sound_localisation/doa_stream.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/time.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/room_simulation.h"

namespace sarmap {
namespace sound {
namespace {

// Interleaved int16 blocks of 512 samples of `mics` through the array's channel map.
void PushAll(DoaStream* stream, const std::vector<std::vector<float>>& mics, int64_t start_utime,
             std::vector<sarmap::doa_t>* doa, std::vector<sarmap::doa_t>* map_doa) {
  const ArrayGeometry& g = stream->geometry();
  int channels = 0;
  for (int c : g.channel_map) channels = std::max(channels, c + 1);
  const int block = 512;
  for (size_t first = 0; first + block <= mics[0].size(); first += block) {
    std::vector<int16_t> data(static_cast<size_t>(block) * channels, 0);
    for (int m = 0; m < g.num_mics(); ++m)
      for (int i = 0; i < block; ++i)
        data[static_cast<size_t>(i) * channels + g.channel_map[m]] =
            static_cast<int16_t>(std::lround(std::clamp(mics[m][first + i], -1.0f, 1.0f) * 32767));
    stream->Push(
        data.data(), block, channels,
        start_utime + common::SecondsToUtime(static_cast<double>(first) / g.sample_rate_hz), doa,
        map_doa);
  }
}

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

// A hidden caller's short call (1 s of real speech, 4 m away in a reverberant room, after 4 s
// of the room's noise) through the node's configuration: the sound map's stream reports her
// in most of the call's blocks, and her direction is classed voice from that call alone.
TEST(DoaStreamTest, ShortCallIsReportedInMostBlocksAndClassedVoice) {
  std::vector<float> call;
  for (int i = 0; i < 6 && call.empty(); ++i) call = testing_util::Speech(i);
  if (call.empty()) GTEST_SKIP() << "no CMU ARCTIC speech under " << SARMAP_DATA_DIR;
  const std::string root = SARMAP_SOURCE_DIR;
  const auto options =
      common::LoadOptions<SoundLocalisationOptions>(root + "/config/sound_localisation.yaml", {});
  const auto array = common::LoadMicArray(root + "/" + options.array);
  DoaStream stream(options, array, root + "/config/arrays/");
  const ArrayGeometry& g = stream.geometry();
  const int fs = g.sample_rate_hz;
  // The call: 1 s from the speech's first loud 16 ms frame.
  double loudest = 0;
  for (float v : call) loudest = std::max(loudest, static_cast<double>(v) * v);
  size_t start = 0;
  while (start < call.size() && static_cast<double>(call[start]) * call[start] < 0.01 * loudest)
    ++start;
  const double call_at_s = 4.0, call_s = 1.0, total_s = 6.0;
  std::vector<float> voice(static_cast<size_t>(total_s * fs), 0.0f);
  for (size_t i = 0; i < static_cast<size_t>(call_s * fs) && start + i < call.size(); ++i)
    voice[static_cast<size_t>(call_at_s * fs) + i] = call[start + i];
  Room room;
  room.size_m = {8, 6, 3};
  room.rt60_s = 0.3;
  const Eigen::Vector3d array_at(2.0, 2.5, 0.8), caller(5.6, 4.2, 1.2);
  Eigen::Matrix3Xd mics = g.positions_m;
  mics.colwise() += array_at;
  // Speech at about 20 dB over the sensor noise at the array (a 62-64 dB call 4-8 m away).
  const auto channels = SimulateRoom(room, mics, {{caller, voice, 1.0}}, voice.size(), 0.002, 21);
  std::vector<sarmap::doa_t> doa, map_doa;
  PushAll(&stream, channels, 1'000'000'000, &doa, &map_doa);
  const Direction truth = g.FromUnit(DoaKind::kAzimuthElevation, (caller - array_at).normalized());
  int call_blocks = 0, reported = 0, voice_blocks = 0, before_call = 0, other_class = 0;
  for (const auto& m : map_doa) {
    const double t = common::UtimeToSeconds(m.header.utime - 1'000'000'000);
    bool near = false, as_voice = false;
    for (const auto& src : m.sources) {
      const bool close =
          std::abs(std::remainder(src.azimuth_rad - truth.azimuth_rad, 2 * M_PI)) < DegToRad(10);
      near |= close;
      as_voice |= close && src.sound_class == sarmap::doa_source_t::SOUND_CLASS_VOICE;
      other_class += close && src.sound_class != sarmap::doa_source_t::SOUND_CLASS_VOICE &&
                     src.sound_class != sarmap::doa_source_t::SOUND_CLASS_UNKNOWN;
    }
    if (t < call_at_s - 0.3) before_call += !m.sources.empty();
    if (t < call_at_s + 0.1 || t > call_at_s + call_s - 0.1) continue;
    ++call_blocks;
    reported += near;
    voice_blocks += as_voice;
  }
  std::printf(
      "call blocks %d: caller reported in %d, classed voice in %d; blocks with a DOA "
      "before the call %d; the caller's DOAs of another class %d\n",
      call_blocks, reported, voice_blocks, before_call, other_class);
  ASSERT_GE(call_blocks, 5);
  EXPECT_GE(reported, call_blocks * 7 / 10);
  EXPECT_GE(voice_blocks, 1);
  EXPECT_EQ(other_class, 0) << "the caller's DOAs classed other than voice";
  // Noise alone: a calibrated false-alarm rate, not a DOA per block.
  EXPECT_LE(before_call, 3);
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
