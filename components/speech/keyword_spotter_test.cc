#include "speech/keyword_spotter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "audio_capture/audio_file.h"
#include "speech/testing/kws_evaluation.h"

namespace sarmap {
namespace speech {
namespace {

std::vector<int16_t> ReadRaw16k(const std::string& path) {
  audio::AudioFileReader r(path, audio::RawFormat{16000, 1, "s16le"});
  std::vector<int16_t> all, block;
  while (r.Read(4096, &block) > 0) all.insert(all.end(), block.begin(), block.end());
  return all;
}

TEST(KeywordSpotterRealData, DecodesGoForwardExactly) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/pocketsphinx_test/goforward.raw";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  KeywordOptions full;
  full.full_decoding = true;
  full.max_utterance_s = 0;
  KeywordSpotter spotter(full);
  double conf = 0;
  EXPECT_EQ(spotter.DecodeText(ReadRaw16k(path), &conf), "go forward ten meters");
  // Keyword mode with the test's own keyword list: "forward" and "meters" are found.
  KeywordOptions o;
  o.keywords = {"forward", "meters"};
  o.thresholds = {1e-20};
  o.max_utterance_s = 0;  // a 2.8 s sentence, not a call
  KeywordSpotter kws(o);
  const auto r = kws.Decode(ReadRaw16k(path));
  std::vector<std::string> found;
  for (const auto& h : r.keywords) found.push_back(h.keyword);
  EXPECT_NE(std::find(found.begin(), found.end(), "forward"), found.end());
  EXPECT_NE(std::find(found.begin(), found.end(), "meters"), found.end());
  for (const auto& h : r.keywords) {
    EXPECT_GT(h.confidence, 0.5);
    EXPECT_LE(h.start_s, h.end_s);
  }
}

// Call shape: an utterance longer than max_utterance_s cannot hold a call and is not decoded;
// acoustic verification yields a finite per-frame log-likelihood ratio for a real keyword.
TEST(KeywordSpotterRealData, CallShapeAndVerification) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/pocketsphinx_test/goforward.raw";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  const auto samples = ReadRaw16k(path);  // about 2.5 s
  KeywordOptions o;
  o.keywords = {"forward", "go forward"};
  o.thresholds = {1e-20};
  o.max_utterance_s = 1.0;
  KeywordSpotter short_only(o);
  EXPECT_TRUE(short_only.Decode(samples).keywords.empty());
  o.max_utterance_s = 0;
  o.verify_acoustic = true;
  o.verify_min_llr = -1e9;
  KeywordSpotter verified(o);
  const auto r = verified.Decode(samples);
  ASSERT_FALSE(r.keywords.empty());
  // "forward" inside "go forward" is one call: only the longer phrase is kept.
  EXPECT_EQ(r.keywords.size(), 1u);
  EXPECT_EQ(r.keywords[0].keyword, "go forward");
  EXPECT_TRUE(r.keywords[0].verified);
  EXPECT_TRUE(std::isfinite(r.keywords[0].verify_llr));
  EXPECT_NEAR(r.keywords[0].utterance_s, samples.size() / 16000.0, 1e-9);
}

TEST(KeywordSpotter, UnknownWordIsAClearError) {
  KeywordOptions o;
  o.keywords = {"xqzzyv"};
  try {
    KeywordSpotter k(o);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not in"), std::string::npos) << e.what();
  }
}

// The evaluation set: num_calls espeak-ng calls at call_snr_db in noise (no other talker), and
// negative_minutes of other speech.
KwsEvalOptions CallsInNoise(int num_calls, double negative_minutes, double call_snr_db) {
  KwsEvalOptions o;
  o.num_calls = num_calls;
  o.negative_minutes = negative_minutes;
  o.call_snr_db = call_snr_db;
  o.babble_db = -100;
  o.data_dir = SARMAP_DATA_DIR;
  return o;
}

// The most permissive keyword search (threshold 1e-40, no confidence cut), the default rule.
KeywordOptions SpotEverything() {
  KeywordOptions k;
  k.thresholds = {1e-40};
  k.min_confidence = 0;
  return k;
}

// Calls for help rendered by espeak-ng at test time (varied voices, rates, pitches) in noise
// (20 dB), and other speech (real recordings + espeak sentences) in noise as negatives. Pins the
// keyword-only recall without and with the default call-shape rule; false alarms are printed (the
// full curve: sarmap-log kws-eval, see README; it does not meet 1 per 10 minutes).
TEST(KeywordSpotterSimulated, CallsForHelpInNoise) {
  if (!EspeakAvailable()) GTEST_SKIP() << "espeak-ng not installed";
  const KwsEvalOptions o = CallsInNoise(8, 0.25, 20);
  const auto data = MakeKwsEvalData(o);
  ASSERT_EQ(data.positives.size(), 8u);
  KeywordOptions k = SpotEverything();
  k.max_utterance_s = 0;
  const auto rs = EvaluateKwsSweep(data, k, VadOptions{}, o, {0.0}, {0.0, KeywordOptions{}.max_utterance_s});
  ASSERT_EQ(rs.size(), 2u);
  for (const auto& r : rs)
    std::printf("simulated calls (SNR 20 dB), threshold 1e-40, max utterance %.1f s: recall %d/%d, 'help' false "
                "alarms %d in %.2f min of other speech (%.0f per 10 min), other keywords %d\n",
                r.max_utterance_s, r.hits, r.calls, r.target_false_alarms, r.negative_minutes,
                r.false_alarms_per_10_min, r.other_false_alarms);
  EXPECT_GE(rs[0].recall, 0.85);
  EXPECT_GE(rs[1].recall, 0.85);
  EXPECT_LE(rs[1].target_false_alarms, rs[0].target_false_alarms);
}

// The multichannel path with the default call-shape rule (calls at most 1.8 s): calls rendered
// on the ReSpeaker array in an anechoic room, the pinkish noise a point source that the caller's
// MVDR beam nulls. The beam's residual jumps 4-5 dB from frame to frame; with a fixed 8 dB
// threshold over the floor the VAD read it as speech, every segment ran to the 6 s cap, and the
// rule dropped every call. With the threshold raised by that fluctuation the
// short calls pass.
TEST(KeywordSpotterSimulated, CallsOnACleanBeamPassTheCallShapeRule) {
  if (!EspeakAvailable()) GTEST_SKIP() << "espeak-ng not installed";
  // "help", "help me", "please help", "somebody help", "help help"
  const auto data = MakeKwsEvalData(CallsInNoise(5, 0, 10));
  ASSERT_EQ(data.positives.size(), 5u);
  const KeywordOptions k = SpotEverything();
  ASSERT_GT(k.max_utterance_s, 0);  // the default rule is on
  const std::string array = std::string(SARMAP_SOURCE_DIR) + "/config/arrays/respeaker4.yaml";
  const int with_fluctuation = KwsArrayRecall(data, array, k, 60, -60, VadOptions{}).hits;
  VadOptions fixed;
  fixed.fluctuation_factor = 0;
  const int with_fixed_threshold = KwsArrayRecall(data, array, k, 60, -60, fixed).hits;
  std::printf("respeaker4 beam, call-shape rule %.1f s: %d/5 calls heard (fixed 8 dB threshold: %d/5)\n",
              k.max_utterance_s, with_fluctuation, with_fixed_threshold);
  EXPECT_GE(with_fluctuation, 4);
  EXPECT_EQ(with_fixed_threshold, 0);
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
