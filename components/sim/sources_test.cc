#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "sim/appearance.h"
#include "sim/sound_sources.h"

namespace sarmap {
namespace sim {
namespace {

double Rms(const std::vector<float>& x) {
  double e = 0;
  for (float v : x) e += static_cast<double>(v) * v;
  return std::sqrt(e / std::max<size_t>(1, x.size()));
}

TEST(SourcesTest, VoiceEventsCycleThroughTheClips) {
  SoundSource s;
  s.kind = SourceKind::kVoice;
  s.start_s = 1.0;
  s.every_s = 3.0;
  std::vector<std::vector<float>> clips = {std::vector<float>(8000, 1.0f), std::vector<float>(16000, -1.0f)};
  SourceSignal signal(s, clips, 16000, 1);
  EXPECT_FALSE(signal.ActiveAt(0.9));
  EXPECT_TRUE(signal.ActiveAt(1.2));   // clip 0: 0.5 s
  EXPECT_FALSE(signal.ActiveAt(1.6));
  EXPECT_TRUE(signal.ActiveAt(4.9));   // clip 1: 1 s from 4.0
  EXPECT_TRUE(signal.ActiveAt(7.3));   // clip 0 again from 7.0
  EXPECT_FALSE(signal.ActiveAt(7.6));
  std::vector<float> out(1600);
  signal.Render(static_cast<int64_t>(4.2 * 16000), 1600, out.data());
  EXPECT_FLOAT_EQ(out[0], -1.0f);
}

TEST(SourcesTest, ContinuousVoiceAndScheduledAlarmMusicNoise) {
  SoundSource voice;
  voice.continuous = true;
  voice.gap_s = 0.5;
  SourceSignal v(voice, {std::vector<float>(16000, 1.0f)}, 16000, 1);
  EXPECT_TRUE(v.ActiveAt(0.5));
  EXPECT_FALSE(v.ActiveAt(1.2));
  EXPECT_TRUE(v.ActiveAt(1.6));  // next cycle
  for (SourceKind kind : {SourceKind::kAlarm, SourceKind::kMusic, SourceKind::kNoise}) {
    SoundSource s;
    s.kind = kind;
    s.start_s = 0.5;
    s.every_s = 2.0;
    s.duration_s = 1.0;
    SourceSignal signal(s, {}, 16000, 3);
    EXPECT_FALSE(signal.ActiveAt(0.2));
    EXPECT_TRUE(signal.ActiveAt(1.0));
    EXPECT_FALSE(signal.ActiveAt(2.0));
    EXPECT_TRUE(signal.ActiveAt(2.6));
    std::vector<float> on(8000), off(4000);
    signal.Render(0, 4000, off.data());  // t < 0.5: silent
    signal.Render(4000, 8000, on.data());   // 0.25 .. 0.75 s: half on
    EXPECT_EQ(Rms(off), 0.0) << SourceKindName(kind);
    std::vector<float> active(on.begin() + 4000, on.end());
    EXPECT_NEAR(Rms(active), 1.0, 0.3) << SourceKindName(kind);  // unit RMS while active
  }
}

TEST(SourcesTest, RealVoiceClipsLoadResampledAndNormalised) {
  const std::string wav = std::string(SARMAP_DATA_DIR) + "/audio/cmu_arctic/cmu_arctic_us_aew_a0001.wav";
  if (std::system(("test -f " + wav).c_str()) != 0) GTEST_SKIP() << "shared data missing: " << wav;
  std::string error;
  const std::vector<float> clip = LoadClip(wav, 16000, &error);
  ASSERT_FALSE(clip.empty()) << error;
  EXPECT_NEAR(Rms(clip), 1.0, 1e-3);
  EXPECT_GT(clip.size(), 16000u * 2);
  const std::vector<float> raw = LoadClip(std::string(SARMAP_DATA_DIR) + "/audio/pocketsphinx_test/goforward.raw", 16000, &error);
  EXPECT_GT(raw.size(), 16000u);
  const std::vector<float> down = Resample(clip, 16000, 8000);
  EXPECT_NEAR(static_cast<double>(down.size()), clip.size() / 2.0, 1.0);
  EXPECT_TRUE(LoadClip("/nonexistent.wav", 16000, &error).empty());
  EXPECT_NE(error.find("/nonexistent.wav"), std::string::npos);
}

TEST(SourcesTest, EspeakPhrasesWhenInstalled) {
  if (std::system("command -v espeak-ng > /dev/null 2>&1") != 0) GTEST_SKIP() << "espeak-ng not installed";
  std::string error;
  const std::string cache = ::testing::TempDir() + "/sarmap_sim_espeak_test";
  const std::vector<float> help = EspeakClip("help", cache, 16000, &error);
  ASSERT_FALSE(help.empty()) << error;
  EXPECT_GT(help.size(), 16000u / 5);  // a word: a few hundred ms
  EXPECT_LT(help.size(), 16000u * 2);
  EXPECT_EQ(EspeakClip("help", cache, 16000, &error).size(), help.size());  // from the cache
}

TEST(AppearanceTest, RealPhotosOrADrawnFigureWithAWarning) {
  std::string warning;
  const auto none = LoadAppearances("/nonexistent/data", 3, &warning);
  EXPECT_FALSE(warning.empty());
  ASSERT_EQ(none.size(), 3u);
  EXPECT_NE(none[0].origin.find("drawn"), std::string::npos);
  const std::string tud = std::string(SARMAP_DATA_DIR) + "/vision/rgb/tud_campus/gt/gt.txt";
  if (std::system(("test -f " + tud).c_str()) != 0) GTEST_SKIP() << "shared data missing: " << tud;
  warning.clear();
  const auto real = LoadAppearances(SARMAP_DATA_DIR, 8, &warning);
  EXPECT_TRUE(warning.empty()) << warning;
  EXPECT_EQ(real.size(), 8u);
  for (const Appearance& a : real) {
    EXPECT_EQ(a.rgb.size(), static_cast<size_t>(a.width) * a.height * 3);
    EXPECT_NEAR(a.person_bottom - a.person_top, 0.75, 0.01);  // HOG's margin kept
  }
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
