#include "speech/enhancer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "audio_capture/audio_file.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/room_simulation.h"

namespace sarmap {
namespace speech {
namespace {

using sound::DegToRad;

// Signal-to-residual ratio (dB) of `y` against reference `s`, after the best alignment
// (lag within +-max_lag) and gain.
double AlignedSnrDb(const std::vector<float>& y, const std::vector<float>& s, size_t from, size_t to, int max_lag) {
  double best = -1e9;
  for (int lag = -max_lag; lag <= max_lag; ++lag) {
    double ys = 0, ss = 0, yy = 0;
    for (size_t i = from; i < to; ++i) {
      const long j = static_cast<long>(i) - lag;
      if (j < 0 || j >= static_cast<long>(s.size()) || i >= y.size()) continue;
      ys += y[i] * s[j];
      ss += s[j] * s[j];
      yy += y[i] * y[i];
    }
    if (ss <= 0 || yy <= 0) continue;
    const double g = ys / ss;
    const double signal = g * g * ss, residual = std::max(yy - 2 * g * ys + signal, 1e-12);
    best = std::max(best, 10 * std::log10(signal / residual));
  }
  return best;
}

TEST(MultiBeamEnhancer, MvdrAndPostFilterBeatOneMicrophoneAgainstADirectionalNoise) {
  auto speech = sound::testing_util::Speech(0);
  if (speech.empty()) GTEST_SKIP() << "shared data missing: audio/cmu_arctic";
  const auto g = sound::testing_util::LoadArray("cube8");
  sound::Room room;
  const Eigen::Vector3d centre(3, 2.5, 1.2);
  const size_t lead = 32000, n = lead + speech.size();
  std::vector<float> target(n, 0.0f);
  std::copy(speech.begin(), speech.end(), target.begin() + lead);
  const double az_t = DegToRad(30), az_n = DegToRad(150);
  const Eigen::Vector3d ut(std::cos(az_t), std::sin(az_t), 0), un(std::cos(az_n), std::sin(az_n), 0);
  // Interferer: continuous noise from 150 deg, as loud as the talker (0 dB), plus sensor noise.
  auto noise = sound::testing_util::WhiteNoise(n, 11);
  const auto mics = sound::SimulateRoom(room, g.positions_m.colwise() + centre,
                                        {{centre + 2.0 * ut, target, 0.5}, {centre + 2.0 * un, noise, 0.5}}, n, 0.0005, 12);
  // Reference: the talker alone at the array centre.
  const auto clean = sound::SimulateRoom(room, centre, {{centre + 2.0 * ut, target, 0.5}}, n, 0.0, 13)[0];
  std::vector<int16_t> pcm = audio::ToInterleavedInt16(mics, 0, n);
  auto run = [&](const std::string& beamformer, bool post) {
    EnhancerOptions o;
    o.beamformer = beamformer;
    o.post_filter = post;
    MultiBeamEnhancer e(g, o);
    std::map<int64_t, std::vector<float>> out;
    for (size_t i = 0; i < n; i += 512)
      e.Push(pcm.data() + i * g.num_mics(), static_cast<int>(std::min<size_t>(512, n - i)), g.num_mics(),
             {{7, ut}}, &out);
    return out[7];
  };
  const double mic = AlignedSnrDb(mics[0], clean, lead, n, 40);
  const double ds = AlignedSnrDb(run("delay_and_sum", false), clean, lead, n, 400);
  const double mvdr = AlignedSnrDb(run("mvdr", false), clean, lead, n, 400);
  const double mvdr_pf = AlignedSnrDb(run("mvdr", true), clean, lead, n, 400);
  std::printf("SNR vs clean talker: mic 0 %.1f dB, delay-and-sum %.1f dB, MVDR %.1f dB, MVDR + post-filter %.1f dB\n",
              mic, ds, mvdr, mvdr_pf);
  EXPECT_GT(ds, mic + 3);
  EXPECT_GT(mvdr, ds + 3);
  EXPECT_GT(mvdr_pf, mic + 6);
}

// Every utterance the detector finds in `x`, its end included.
std::vector<Utterance> Utterances(const std::vector<float>& x, int sample_rate_hz,
                                  const VadOptions& options) {
  VoiceActivityDetector vad(sample_rate_hz, options);
  std::vector<Utterance> u;
  vad.Push(x.data(), x.size(), &u);
  vad.Flush(&u);
  return u;
}

TEST(VoiceActivityDetector, FindsOneUtteranceWithItsBounds) {
  std::vector<float> x(48000, 0.0f);
  auto noise = sound::testing_util::WhiteNoise(48000, 3);
  for (size_t i = 0; i < x.size(); ++i) x[i] = 0.001f * noise[i];
  for (size_t i = 16000; i < 32000; ++i) x[i] += 0.2f * std::sin(2 * M_PI * 300 * i / 16000.0) * (1 + 0.5f * std::sin(i * 0.001f));
  const std::vector<Utterance> u = Utterances(x, 16000, VadOptions{});
  ASSERT_EQ(u.size(), 1u);
  EXPECT_NEAR(u[0].start_sample / 16000.0, 1.0, 0.05);
  EXPECT_NEAR(u[0].end_sample / 16000.0, 2.0, 0.35);
  EXPECT_EQ(static_cast<int64_t>(u[0].samples.size()), u[0].end_sample - u[0].samples_start);
}

// Exact zeros (a beam's first overlap-add samples, a dropout filled with zeros) must not drag
// the noise floor down: after 0.5 s of zeros, noise and then a 1 s tone give one ~1 s utterance,
// not one that starts with the noise.
TEST(VoiceActivityDetector, DigitalSilenceDoesNotSetTheFloor) {
  auto noise = sound::testing_util::WhiteNoise(56000, 4);
  std::vector<float> x(56000, 0.0f);
  for (size_t i = 8000; i < x.size(); ++i) x[i] = 0.001f * noise[i];
  for (size_t i = 32000; i < 48000; ++i) x[i] += 0.2f * std::sin(2 * M_PI * 300 * i / 16000.0);
  const std::vector<Utterance> u = Utterances(x, 16000, VadOptions{});
  ASSERT_EQ(u.size(), 1u);
  EXPECT_NEAR(u[0].start_sample / 16000.0, 2.0, 0.05);
  EXPECT_LT((u[0].end_sample - u[0].start_sample) / 16000.0, 1.5);
}

// The residual of a beam whose MVDR nulled a point noise and whose post-filter removed the
// rest jumps by several dB from one 16 ms frame to the next (a simulated anechoic scene).
// Against its minimum, half its frames read as speech and utterances ran to the 6 s cap, so
// the call-shape rule dropped every call. Here: white noise whose level is redrawn every frame
// (std 5 dB), then a 0.8 s tone 35 dB above it. With the threshold raised by the noise's own
// fluctuation there is one utterance, at the tone; with the fixed 8 dB threshold there is not.
TEST(VoiceActivityDetector, AResidualThatJumpsFromFrameToFrameIsNotSpeech) {
  const int rate = 16000, frame = 256;
  const size_t n = 7 * rate, tone_begin = 5 * rate, tone_end = tone_begin + rate * 8 / 10;
  auto noise = sound::testing_util::WhiteNoise(n, 5);
  std::mt19937 rng(7);
  std::normal_distribution<double> level_db(0.0, 5.0);
  std::vector<float> x(n, 0.0f);
  double gain = 1;
  for (size_t i = 0; i < n; ++i) {
    if (i % frame == 0) gain = std::pow(10.0, level_db(rng) / 20);
    x[i] = static_cast<float>(1e-4 * gain * noise[i]);
  }
  for (size_t i = tone_begin; i < tone_end; ++i) x[i] += 0.0056f * std::sin(2 * M_PI * 300 * i / rate);
  // The utterances that start after the first 1.5 s, in which the threshold learns the noise.
  auto run = [&](const VadOptions& o) {
    std::vector<Utterance> after_learning;
    for (const auto& a : Utterances(x, rate, o))
      if (a.start_sample > 3 * rate / 2) after_learning.push_back(a);
    return after_learning;
  };
  // Whether the tone is the only utterance, with its own bounds.
  auto tone_alone = [&](const std::vector<Utterance>& u) {
    return u.size() == 1 && std::abs(u[0].start_sample / static_cast<double>(rate) - 5.0) < 0.1 &&
           (u[0].end_sample - u[0].start_sample) / static_cast<double>(rate) < 1.3;
  };
  EXPECT_TRUE(tone_alone(run(VadOptions{})));
  VadOptions fixed_threshold;
  fixed_threshold.fluctuation_factor = 0;
  EXPECT_FALSE(tone_alone(run(fixed_threshold)));
}

TEST(Resample, PreservesASineAcrossRates) {
  std::vector<float> x(22050);
  for (size_t i = 0; i < x.size(); ++i) x[i] = std::sin(2 * M_PI * 1000 * i / 22050.0);
  const auto y = Resample(x, 22050, 16000);
  ASSERT_NEAR(static_cast<double>(y.size()), 16000, 1);
  for (size_t i = 100; i < 15900; i += 997) EXPECT_NEAR(y[i], std::sin(2 * M_PI * 1000 * i / 16000.0), 0.01);
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
