// The source classifier on real speech (shared/data, skipped if absent) and on synthesised
// alarms, machinery, noise and music; the directional classifier on a two-source room.
#include "sound_localisation/source_class.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "audio_capture/audio_file.h"
#include "sound_localisation/stft.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/room_simulation.h"

namespace sarmap {
namespace sound {
namespace {

constexpr int kRate = 16000;

std::vector<float> Normalised(std::vector<float> x) {
  double e = 0;
  for (float v : x) e += v * v;
  const double g = 1.0 / std::sqrt(e / std::max<size_t>(1, x.size()) + 1e-20);
  for (float& v : x) v = static_cast<float>(v * g);
  return x;
}

// Unit-RMS signal plus white noise `snr_db` below it.
std::vector<float> WithNoise(std::vector<float> x, double snr_db, uint32_t seed) {
  x = Normalised(std::move(x));
  std::mt19937 rng(seed);
  std::normal_distribution<float> d(0.0f, static_cast<float>(std::pow(10.0, -snr_db / 20)));
  for (float& v : x) v += d(rng);
  return x;
}

SoundClassEstimate ClassifyMono(const std::vector<float>& x, SourceClassOptions options = {}) {
  SoundClassifier classifier(options, kRate);
  MultichannelStft stft(1, options.fft_size, options.hop_size);
  std::vector<std::vector<float>> channels{x};
  std::vector<float> power(options.fft_size / 2 + 1);
  stft.PushFloat(channels, 0, x.size(), [&](const Eigen::MatrixXcf& s, int64_t end) {
    for (int k = 0; k < s.rows(); ++k) power[k] = std::norm(s(k, 0));
    classifier.AddFrame(power, end);
  });
  return classifier.Classify();
}

// As a localiser's reports decide it: only the frames of (begin_s, end_s] sound.
SoundClassEstimate ClassifyReported(const std::vector<float>& x, double begin_s, double end_s,
                                    const SourceClassOptions& options) {
  SoundClassifier classifier(options, kRate);
  MultichannelStft stft(1, options.fft_size, options.hop_size);
  std::vector<std::vector<float>> channels{x};
  std::vector<float> power(options.fft_size / 2 + 1);
  stft.PushFloat(channels, 0, x.size(), [&](const Eigen::MatrixXcf& s, int64_t end) {
    for (int k = 0; k < s.rows(); ++k) power[k] = std::norm(s(k, 0));
    classifier.AddFrame(power, end, 0);
  });
  classifier.MarkPresent(static_cast<int64_t>(begin_s * kRate),
                         static_cast<int64_t>(end_s * kRate));
  return classifier.Classify();
}

std::string Describe(const SoundClassEstimate& e) {
  char buf[256];
  std::snprintf(
      buf, sizeof(buf),
      "%s (conf %.2f): present %.2f s, flatness %.3f, tonality %.3f, flux %.3f, level std %.1f dB, "
      "syllabic %.3f, peak share %.2f",
      SoundClassName(e.sound_class), e.confidence, e.features.present_s, e.features.flatness,
      e.features.tonality, e.features.flux, e.features.level_std_db, e.features.syllabic,
      e.features.peak_share);
  return buf;
}

// Synthesised classes (seconds of signal at kRate).
std::vector<float> TwoToneSiren(double seconds, double f1, double f2) {
  std::vector<float> x(static_cast<size_t>(seconds * kRate));
  for (size_t i = 0; i < x.size(); ++i) {
    const double t = static_cast<double>(i) / kRate;
    const double f = std::fmod(t, 1.0) < 0.5 ? f1 : f2;
    double v = 0;
    for (int h = 1; h <= 7; h += 2) v += std::sin(2 * M_PI * f * h * t) / h;
    x[i] = static_cast<float>(v);
  }
  return x;
}

std::vector<float> Beeper(double seconds, double hz, double on_s, double off_s) {
  std::vector<float> x(static_cast<size_t>(seconds * kRate));
  for (size_t i = 0; i < x.size(); ++i) {
    const double t = static_cast<double>(i) / kRate;
    x[i] =
        std::fmod(t, on_s + off_s) < on_s ? static_cast<float>(std::sin(2 * M_PI * hz * t)) : 0.0f;
  }
  return x;
}

// Fan / engine: low-passed noise, white noise and a hum with its harmonics.
std::vector<float> Machinery(double seconds, double hum_hz, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> d(0, 1);
  std::vector<float> x(static_cast<size_t>(seconds * kRate));
  double low = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double t = static_cast<double>(i) / kRate;
    low = 0.97 * low + 0.03 * d(rng);
    double v = 0.8 * low / std::sqrt(0.03 / 1.97) + 0.6 * d(rng);
    for (int h = 1; h <= 6; ++h) v += 0.5 / h * std::sin(2 * M_PI * hum_hz * h * t);
    x[i] = static_cast<float>(v);
  }
  return x;
}

// A tune: plucked harmonic notes, 0.22 s each, over a bass line.
std::vector<float> Tune(double seconds, double note_s) {
  static const double kNotes[8] = {523.25, 659.25, 783.99, 1046.5, 783.99, 659.25, 587.33, 698.46};
  std::vector<float> x(static_cast<size_t>(seconds * kRate));
  for (size_t i = 0; i < x.size(); ++i) {
    const double t = static_cast<double>(i) / kRate;
    const int idx = static_cast<int>(std::floor(t / note_s)) % 8;
    const double local = std::fmod(t, note_s);
    const double env = std::exp(-local * 9.0) * std::min(1.0, local * 200.0);
    double v = 0;
    for (int h = 1; h <= 4; ++h) v += std::sin(2 * M_PI * kNotes[idx] * h * t) / (h * h);
    x[i] = static_cast<float>(v * env + 0.4 * std::sin(2 * M_PI * (idx < 4 ? 130.81 : 146.83) * t));
  }
  return x;
}

std::vector<std::string> SpeechFiles() {
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/audio/";
  std::vector<std::string> out;
  for (const char* sub :
       {"cmu_arctic", "pocketsphinx_test/librivox", "pocketsphinx_test/cards", "sphinx4_digits"}) {
    if (!std::filesystem::is_directory(dir + sub)) continue;
    for (const auto& e : std::filesystem::directory_iterator(dir + sub))
      if (e.path().extension() == ".wav") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SourceClassTest, RealSpeechIsVoice) {
  const auto files = SpeechFiles();
  if (files.empty()) GTEST_SKIP() << "no speech recordings under " << SARMAP_DATA_DIR << "/audio";
  int right = 0;
  for (size_t i = 0; i < files.size(); ++i) {
    const auto buffer = audio::ReadAudioFile(files[i]);
    ASSERT_EQ(buffer.sample_rate_hz, kRate) << files[i];
    const auto e = ClassifyMono(WithNoise(buffer.channels[0], 25, static_cast<uint32_t>(7 + i)));
    std::printf("%s: %s\n", std::filesystem::path(files[i]).filename().c_str(),
                Describe(e).c_str());
    right += e.sound_class == SoundClass::kVoice;
  }
  EXPECT_GE(right, static_cast<int>(0.9 * files.size())) << right << " of " << files.size();
}

TEST(SourceClassTest, SynthesisedClasses) {
  struct Case {
    std::string name;
    std::vector<float> signal;
    SoundClass expected;
  };
  const std::vector<Case> cases = {
      {"siren 960/770 Hz", TwoToneSiren(4, 960, 770), SoundClass::kAlarm},
      {"siren 2.8/2.2 kHz", TwoToneSiren(4, 2800, 2200), SoundClass::kAlarm},
      {"beeper 2.8 kHz", Beeper(4, 2800, 0.5, 0.5), SoundClass::kAlarm},
      {"beeper 3.1 kHz fast", Beeper(4, 3100, 0.15, 0.1), SoundClass::kAlarm},
      {"steady tone 1.5 kHz", Beeper(4, 1500, 10, 0), SoundClass::kAlarm},
      {"machinery 50 Hz", Machinery(4, 50, 1), SoundClass::kMachinery},
      {"machinery 120 Hz", Machinery(4, 120, 2), SoundClass::kMachinery},
      {"white noise", testing_util::WhiteNoise(4 * kRate, 3), SoundClass::kMachinery},
      {"tune 0.22 s notes", Tune(4, 0.22), SoundClass::kMusic},
      {"tune 0.4 s notes", Tune(4, 0.4), SoundClass::kMusic},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const auto e = ClassifyMono(WithNoise(cases[i].signal, 25, static_cast<uint32_t>(100 + i)));
    std::printf("%s: %s\n", cases[i].name.c_str(), Describe(e).c_str());
    EXPECT_EQ(e.sound_class, cases[i].expected) << cases[i].name << ": " << Describe(e);
  }
}

// The first `seconds` of a recording's speech (from its first frame within 20 dB of its
// loudest), with 0.5 s of silence either side: one short call.
std::vector<float> ShortCall(const std::vector<float>& x, double seconds) {
  const size_t hop = 256;
  double loudest = 0;
  std::vector<double> energy;
  for (size_t i = 0; i + hop <= x.size(); i += hop) {
    double e = 0;
    for (size_t j = i; j < i + hop; ++j) e += x[j] * x[j];
    energy.push_back(e);
    loudest = std::max(loudest, e);
  }
  size_t start = 0;
  while (start < energy.size() && energy[start] < loudest * 0.01) ++start;
  std::vector<float> out(kRate / 2, 0.0f);
  const size_t first = start * hop, n = static_cast<size_t>(seconds * kRate);
  for (size_t i = first; i < std::min(x.size(), first + n); ++i) out.push_back(x[i]);
  out.insert(out.end(), kRate / 2, 0.0f);
  return out;
}

// A short call is classed from the little of it there is: the first 0.5 and 1 s of each
// recording's speech are voice; tones, noise, machinery and a siren as short are not.
TEST(SourceClassTest, ShortCallsAreVoiceShortTonesAndNoiseAreNot) {
  const auto files = SpeechFiles();
  if (files.empty()) GTEST_SKIP() << "no speech recordings under " << SARMAP_DATA_DIR << "/audio";
  const SourceClassOptions options;
  for (double seconds : {0.5, 1.0}) {
    int right = 0;
    for (size_t i = 0; i < files.size(); ++i) {
      const auto buffer = audio::ReadAudioFile(files[i]);
      const auto call = ShortCall(Normalised(buffer.channels[0]), seconds);
      const auto e = ClassifyReported(WithNoise(call, 25, static_cast<uint32_t>(40 + i)), 0.5,
                                      0.5 + seconds, options);
      std::printf("%.1f s of %s: %s\n", seconds, std::filesystem::path(files[i]).filename().c_str(),
                  Describe(e).c_str());
      right += e.sound_class == SoundClass::kVoice;
    }
    // Of half a second of speech, 0.19-0.5 s are within 20 dB of its loudest frame.
    EXPECT_GE(right, static_cast<int>((seconds < 1 ? 0.8 : 0.9) * files.size()))
        << right << " of " << files.size() << " calls of " << seconds << " s";
  }
  auto padded = [](std::vector<float> x) {
    x = Normalised(std::move(x));
    x.insert(x.begin(), kRate / 2, 0.0f);
    x.insert(x.end(), kRate / 2, 0.0f);
    return x;
  };
  for (double seconds : {0.5, 1.0, 2.0}) {
    const std::vector<std::pair<std::string, std::vector<float>>> cases = {
        {"tone 1.5 kHz", Beeper(seconds, 1500, 10, 0)},
        {"tone 3 kHz", Beeper(seconds, 3000, 10, 0)},
        {"beeper 2.8 kHz", Beeper(seconds, 2800, 0.15, 0.1)},
        {"siren", TwoToneSiren(seconds, 2800, 2200)},
        {"white noise", testing_util::WhiteNoise(static_cast<size_t>(seconds * kRate), 11)},
        {"machinery 50 Hz", Machinery(seconds, 50, 12)},
    };
    for (size_t i = 0; i < cases.size(); ++i) {
      const auto e = ClassifyReported(WithNoise(padded(cases[i].second), 25, 200 + i), 0.5,
                                      0.5 + seconds, options);
      std::printf("%.1f s of %s: %s\n", seconds, cases[i].first.c_str(), Describe(e).c_str());
      EXPECT_NE(e.sound_class, SoundClass::kVoice)
          << seconds << " s of " << cases[i].first << ": " << Describe(e);
      // The tones, the beeper and the siren are clear alarms, decided as early as a voice;
      // noise and machinery wait for min_present_s.
      const bool tonal = i < 4;
      if (tonal || seconds >= options.min_present_s) {
        EXPECT_EQ(e.sound_class, tonal ? SoundClass::kAlarm : SoundClass::kMachinery)
            << seconds << " s of " << cases[i].first << ": " << Describe(e);
      } else {
        EXPECT_EQ(e.sound_class, SoundClass::kUnknown)
            << seconds << " s of " << cases[i].first << ": " << Describe(e);
      }
    }
  }
}

TEST(SourceClassTest, TooLittleSoundIsUnknown) {
  // 0.15 s of a beep: less than min_voice_present_s.
  const auto beep = ClassifyMono(WithNoise(Beeper(0.15, 2800, 10, 0), 25, 5));
  EXPECT_EQ(beep.sound_class, SoundClass::kUnknown) << Describe(beep);
  // 0.5 s of a tune is not a voice (on its first few notes it looks like an alarm).
  const auto tune = ClassifyMono(WithNoise(Tune(0.5, 0.1), 25, 6));
  EXPECT_NE(tune.sound_class, SoundClass::kVoice) << Describe(tune);
  // The same beep for 0.3 s is a clear alarm.
  const auto alarm = ClassifyMono(WithNoise(Beeper(0.3, 2800, 10, 0), 25, 5));
  EXPECT_EQ(alarm.sound_class, SoundClass::kAlarm) << Describe(alarm);
  SourceClassOptions never;
  never.clear_alarm_tonal_min = 1.5;
  const auto late = ClassifyMono(WithNoise(Beeper(0.3, 2800, 10, 0), 25, 5), never);
  EXPECT_EQ(late.sound_class, SoundClass::kUnknown) << Describe(late);
}

// Three sources at once in a reverberant room (image sources), heard by the ReSpeaker array:
// each direction gets its own class from the bins it explains.
TEST(SourceClassTest, DirectionalClassifierSeparatesThreeSources) {
  std::vector<float> speech;
  for (int i = 0; i < 6; ++i) {
    const auto clip = testing_util::Speech(i);
    if (clip.empty()) GTEST_SKIP() << "no CMU ARCTIC speech under " << SARMAP_DATA_DIR;
    speech.insert(speech.end(), clip.begin(), clip.end());
    speech.insert(speech.end(), kRate / 3, 0.0f);  // pauses between sentences
  }
  const double seconds = 12;
  speech.resize(static_cast<size_t>(seconds * kRate), 0.0f);
  const ArrayGeometry geometry = testing_util::LoadArray("respeaker4");
  Room room;
  room.size_m = {7, 6, 3};
  room.rt60_s = 0.3;
  const Eigen::Vector3d array(3.5, 3.0, 1.0);
  Eigen::Matrix3Xd mics = geometry.positions_m;
  mics.colwise() += array;
  const std::vector<Eigen::Vector3d> where = {{5.5, 4.2, 1.6}, {1.2, 4.5, 1.0}, {2.5, 0.8, 1.4}};
  const std::vector<SoundClass> truth = {SoundClass::kVoice, SoundClass::kMachinery,
                                         SoundClass::kAlarm};
  std::vector<SimSource> sources = {{where[0], Normalised(speech), 1.0},
                                    {where[1], Normalised(Machinery(seconds, 50, 4)), 0.5},
                                    {where[2], Normalised(Beeper(seconds, 2800, 0.5, 0.5)), 0.5}};
  const auto channels =
      SimulateRoom(room, mics, sources, static_cast<size_t>(seconds * kRate), 0.002, 9);
  std::vector<Direction> directions;
  for (const auto& w : where) {
    const Eigen::Vector3d u = (w - array).normalized();
    directions.push_back(geometry.FromUnit(DoaKind::kAzimuthElevation, u));
  }
  DirectionalClassifier classifier(geometry, DoaKind::kAzimuthElevation, SourceClassOptions());
  const size_t block = kRate * 128 / 1000;
  std::vector<SoundClassEstimate> last;
  for (size_t begin = 0; begin + block <= channels[0].size(); begin += block) {
    classifier.PushFloat(channels, begin, block);
    // Every source is reported in every block: the class comes from the bins, not the reports.
    last = classifier.Observe(static_cast<int64_t>(begin), static_cast<int64_t>(begin + block),
                              directions);
  }
  ASSERT_EQ(last.size(), 3u);
  EXPECT_EQ(classifier.num_tracks(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    std::printf("source %zu: %s\n", i, Describe(last[i]).c_str());
    EXPECT_EQ(last[i].sound_class, truth[i]) << "source " << i << ": " << Describe(last[i]);
  }
  // A second stream reads the tracks without touching them; a direction far from all is unknown.
  std::vector<Direction> other = directions;
  other.push_back(
      geometry.FromUnit(DoaKind::kAzimuthElevation, Eigen::Vector3d(0, -1, 0.2).normalized()));
  const auto looked_up = classifier.Lookup(other);
  ASSERT_EQ(looked_up.size(), 4u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(looked_up[i].sound_class, truth[i]);
  EXPECT_EQ(looked_up[3].sound_class, SoundClass::kUnknown);
  EXPECT_EQ(classifier.num_tracks(), 3u);
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
