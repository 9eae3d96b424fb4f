// The simulator's emitters of every kind, as the worlds use them, are told apart by the
// sound classifier (components/sound_localisation/source_class.h): the worlds' sources can be
// scored by class.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "sim/sound_sources.h"
#include "sound_localisation/source_class.h"
#include "sound_localisation/stft.h"

namespace sarmap {
namespace sim {
namespace {

constexpr int kRate = 16000;

// Renders `seconds` of a source (plus white noise noise_rms below its unit level: 0.03 is
// 30 dB) and classifies it.
sound::SoundClassEstimate Classify(const SoundSource& source, std::vector<std::vector<float>> clips,
                                   double from_s, double seconds, float noise_rms = 0.03f,
                                   const sound::SourceClassOptions& options = {}) {
  SourceSignal signal(source, std::move(clips), kRate, 7);
  std::vector<float> x(static_cast<size_t>(seconds * kRate));
  signal.Render(static_cast<int64_t>(from_s * kRate), static_cast<int>(x.size()), x.data());
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, noise_rms);
  for (float& v : x) v += noise(rng);
  sound::SoundClassifier classifier(options, kRate);
  sound::MultichannelStft stft(1, options.fft_size, options.hop_size);
  std::vector<float> power(options.fft_size / 2 + 1);
  stft.PushFloat({x}, 0, x.size(), [&](const Eigen::MatrixXcf& s, int64_t end) {
    for (int k = 0; k < s.rows(); ++k) power[k] = std::norm(s(k, 0));
    classifier.AddFrame(power, end);
  });
  return classifier.Classify();
}

TEST(SimSourceClassTest, EveryKindIsToldApart) {
  SoundSource siren;
  siren.kind = SourceKind::kAlarm;
  SoundSource beeper = siren;
  beeper.tone_hz = 3100;
  beeper.beep_period_s = 0.5;
  SoundSource music;
  music.kind = SourceKind::kMusic;
  SoundSource servers;
  servers.kind = SourceKind::kNoise;
  servers.hum_hz = 50;
  SoundSource air_conditioning;
  air_conditioning.kind = SourceKind::kNoise;
  EXPECT_EQ(Classify(siren, {}, 0, 4).sound_class, sound::SoundClass::kAlarm);
  EXPECT_EQ(Classify(beeper, {}, 0, 4).sound_class, sound::SoundClass::kAlarm);
  EXPECT_EQ(Classify(music, {}, 0, 4).sound_class, sound::SoundClass::kMusic);
  EXPECT_EQ(Classify(servers, {}, 0, 4).sound_class, sound::SoundClass::kMachinery);
  EXPECT_EQ(Classify(air_conditioning, {}, 0, 4).sound_class, sound::SoundClass::kMachinery);
}

TEST(SimSourceClassTest, TheTuneInNoiseHoldsItsPitchAndIsMusic) {
  // In noise 14 dB below it the tune's tonality and flux look like speech's (T 0.60, X 0.13);
  // its notes still hold their pitch (steadiness 0.83; speech 0.00-0.24).
  SoundSource music;
  music.kind = SourceKind::kMusic;
  const auto e = Classify(music, {}, 0, 4, 0.2f);
  EXPECT_EQ(e.sound_class, sound::SoundClass::kMusic);
  EXPECT_GT(e.features.steadiness, 0.7);
  sound::SourceClassOptions without;
  without.sustained_min = 2.0;
  EXPECT_EQ(Classify(music, {}, 0, 4, 0.2f, without).sound_class, sound::SoundClass::kVoice);
}

TEST(SimSourceClassTest, RecordedVoicesAreVoices) {
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/audio/cmu_arctic/";
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no CMU ARCTIC speech under " << dir;
  for (const char* file : {"cmu_arctic_us_aew_a0001.wav", "cmu_arctic_us_axb_a0004.wav"}) {
    std::string error;
    auto clip = LoadClip(dir + file, kRate, &error);
    ASSERT_FALSE(clip.empty()) << error;
    SoundSource voice;
    voice.kind = SourceKind::kVoice;
    voice.every_s = 6;  // as the worlds' callers: a sentence every 6 s
    const double length_s = static_cast<double>(clip.size()) / kRate;
    const auto e = Classify(voice, {clip}, 0, std::min(4.0, length_s));
    EXPECT_EQ(e.sound_class, sound::SoundClass::kVoice) << file;
    EXPECT_LT(e.features.steadiness, 0.3) << file;
    // Through noise as strong as the tune's above, speech's pitch still glides.
    const auto noisy = Classify(voice, {clip}, 0, std::min(4.0, length_s), 0.2f);
    EXPECT_LT(noisy.features.steadiness, 0.3) << file;
    EXPECT_NE(noisy.sound_class, sound::SoundClass::kMusic) << file;
    EXPECT_NE(noisy.sound_class, sound::SoundClass::kAlarm) << file;
  }
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
