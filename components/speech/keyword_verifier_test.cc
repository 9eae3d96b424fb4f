#include "speech/keyword_verifier.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "audio_capture/audio_file.h"
#include "common/options.h"
#include "speech/hit_features.h"
#include "speech/keyword_spotter.h"

namespace sarmap {
namespace speech {
namespace {

std::vector<int16_t> Tone(double hz, double seconds, double amplitude) {
  std::vector<int16_t> x(static_cast<size_t>(seconds * 16000));
  for (size_t i = 0; i < x.size(); ++i) x[i] = static_cast<int16_t>(amplitude * std::sin(2 * M_PI * hz * i / 16000.0));
  return x;
}

// Tilt = energy of the first difference over the energy: for a sine of frequency f it is
// |1 - e^{-jw}|^2 = 2 - 2 cos(w), w = 2 pi f / fs; white noise gives 2 (+3.0 dB).
TEST(HitFeatures, TiltAndPitchOfKnownSignals) {
  const auto tone = Tone(200, 1.0, 8000);
  const HitFeatures f = ComputeHitFeatures(tone.data(), tone.size(), 0.0, 1.0, 0.2, 0.8, -0.2);
  const double w = 2 * M_PI * 200 / 16000;
  EXPECT_NEAR(f.tilt_db, 10 * std::log10(2 - 2 * std::cos(w)), 0.05);
  EXPECT_NEAR(f.pitch_hz, 200, 2);
  EXPECT_GT(f.voiced_fraction, 0.9);
  EXPECT_NEAR(f.duration_s, 0.6, 1e-9);
  EXPECT_NEAR(f.ratio_per_s, -0.2 / 0.6, 1e-9);
  EXPECT_NEAR(f.lead_s, 0.2, 1e-9);
  EXPECT_NEAR(f.trail_s, 0.2, 1e-9);
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 3000);
  std::vector<int16_t> noise(16000);
  for (auto& v : noise) v = static_cast<int16_t>(n(rng));
  const HitFeatures g = ComputeHitFeatures(noise.data(), noise.size(), 0.0, 1.0, 0.0, 1.0, -0.2);
  EXPECT_NEAR(g.tilt_db, 10 * std::log10(2.0), 0.1);
  EXPECT_LT(g.voiced_fraction, 0.1);
}

TEST(HitFeatures, PhoneEditDistance) {
  EXPECT_EQ(PhoneEditDistance({"HH", "EH", "L", "P"}, {"HH", "EH", "L", "P"}), 0);
  EXPECT_EQ(PhoneEditDistance({"AE", "OW"}, {"HH", "EH", "L", "P"}), 4);
  EXPECT_EQ(PhoneEditDistance({"HH", "EH", "L"}, {"HH", "EH", "L", "P"}), 1);
  EXPECT_EQ(PhoneEditDistance({}, {"HH"}), 1);
}

// The fit recovers a separating direction: calls with tilt around -6 dB, other speech around
// -10 dB; the verifier accepts the first and rejects the second, and p(midpoint) is about 0.5.
TEST(KeywordVerifier, FitsAndSeparatesOneFeature) {
  std::mt19937 rng(7);
  std::normal_distribution<double> calls(-6, 1), other(-10, 1);
  std::vector<HitFeatures> x;
  std::vector<int> y;
  for (int i = 0; i < 200; ++i) {
    HitFeatures f;
    const bool call = i % 4 == 0;  // unbalanced classes: the fit weighs both equally
    f.tilt_db = call ? calls(rng) : other(rng);
    x.push_back(f);
    y.push_back(call);
  }
  VerifierOptions o = FitKeywordVerifier(x, y, {"tilt_db"});
  common::Validator check;
  common::CheckOptions(o, &check);
  EXPECT_TRUE(check.errors().empty());
  EXPECT_GT(o.weights[0], 0);
  KeywordVerifier v(o);
  HitFeatures a, b, mid;
  a.tilt_db = -6;
  b.tilt_db = -10;
  mid.tilt_db = -8;
  EXPECT_GT(v.Probability(a), 0.9);
  EXPECT_LT(v.Probability(b), 0.1);
  EXPECT_NEAR(v.Probability(mid), 0.5, 0.1);
  EXPECT_TRUE(v.Accept(a));
  EXPECT_FALSE(v.Accept(b));
  o.enabled = false;
  EXPECT_TRUE(KeywordVerifier(o).Accept(b));  // disabled: accepts everything
}

TEST(KeywordVerifier, BadOptionsAreClearErrors) {
  VerifierOptions o;
  o.features = {"tilt_db", "nonsense"};
  common::Validator check;
  common::CheckOptions(o, &check);
  ASSERT_FALSE(check.errors().empty());
  EXPECT_THROW(FeatureValue(HitFeatures(), "nonsense"), std::invalid_argument);
  EXPECT_THROW(FitKeywordVerifier({HitFeatures()}, {1}, {"tilt_db"}), std::invalid_argument);  // one class
}

// In the spotter: a verifier that rejects everything removes the real keyword hits of
// goforward.raw; one that accepts everything keeps them and reports its probability.
TEST(KeywordVerifierRealData, AppliedInTheSpotter) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/pocketsphinx_test/goforward.raw";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  audio::AudioFileReader r(path, audio::RawFormat{16000, 1, "s16le"});
  std::vector<int16_t> samples, block;
  while (r.Read(4096, &block) > 0) samples.insert(samples.end(), block.begin(), block.end());
  KeywordOptions o;
  o.keywords = {"forward"};
  o.thresholds = {1e-20};
  o.max_utterance_s = 0;
  o.verifier.enabled = true;
  o.verifier.features = {"tilt_db", "phone_distance"};
  o.verifier.means = {0, 0};
  o.verifier.scales = {1, 1};
  o.verifier.weights = {0, 0};
  o.verifier.bias = 10;  // p ~ 1
  KeywordSpotter accept(o);
  const auto kept = accept.Decode(samples);
  ASSERT_FALSE(kept.keywords.empty());
  EXPECT_GT(kept.keywords[0].verifier_probability, 0.99);
  EXPECT_LT(kept.keywords[0].features.tilt_db, 0);      // speech: more low- than high-frequency energy
  EXPECT_GE(kept.keywords[0].features.phone_distance, 0);  // the phone loop ran
  EXPECT_FALSE(kept.keywords[0].features.phones.empty());
  o.verifier.bias = -10;
  KeywordSpotter reject(o);
  EXPECT_TRUE(reject.Decode(samples).keywords.empty());
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
