#include "audio_capture/audio_source.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>

namespace sarmap {
namespace audio {
namespace {

std::string TempPath(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / ("sarmap_audio_test_" + name)).string();
}

// 4 channels, 0.5 s at 16 kHz: ch0 sine, ch1 clipped square, ch2 silent, ch3 quiet noise.
std::string MakeTestWav() {
  AudioBuffer b;
  b.sample_rate_hz = 16000;
  b.channels.assign(4, std::vector<float>(8000, 0.0f));
  for (int i = 0; i < 8000; ++i) {
    b.channels[0][i] = 0.3f * std::sin(2 * M_PI * 440 * i / 16000.0);
    b.channels[1][i] = (i / 20) % 2 ? 1.2f : -1.2f;  // beyond full scale: clipped
    b.channels[3][i] = 0.01f * std::sin(1.7f * i);
  }
  const std::string path = TempPath("four.wav");
  WriteWav(path, b);
  return path;
}

// Capture from the test WAV at `speed` (0: as fast as it reads).
CaptureOptions TestWavAtSpeed(double speed) {
  CaptureOptions o;
  o.file = MakeTestWav();
  o.speed = speed;
  return o;
}

// Opening the source fails with `message` in its error.
void ExpectOpenFails(const CaptureOptions& o, const std::string& message) {
  try {
    OpenAudioSource(o);
    FAIL() << "expected an error";
  } catch (const AudioSourceError& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(FileSource, ContiguousBlocksWithSampleCounterAndUtime) {
  CaptureOptions o = TestWavAtSpeed(0);
  o.start_utime = 1000000;
  auto src = OpenAudioSource(o);
  EXPECT_EQ(src->num_channels(), 4);
  EXPECT_EQ(src->sample_rate_hz(), 16000);
  EXPECT_EQ(src->device_id(), "sarmap_audio_test_four");
  AudioBlock b;
  int64_t expected = 0, total = 0;
  while (src->Read(512, &b)) {
    EXPECT_EQ(b.first_sample_index, expected);
    EXPECT_EQ(b.utime, 1000000 + expected * 1000000 / 16000);
    EXPECT_EQ(b.overrun_samples, 0);
    EXPECT_EQ(b.samples.size(), static_cast<size_t>(b.num_frames) * 4);
    expected += b.num_frames;
    total += b.num_frames;
  }
  EXPECT_EQ(total, 8000);
}

TEST(FileSource, RealTimePacingAndSpeed) {
  const CaptureOptions o = TestWavAtSpeed(4.0);  // 0.5 s of audio in about 0.125 s
  auto src = OpenAudioSource(o);
  AudioBlock b;
  const auto t0 = std::chrono::steady_clock::now();
  int64_t n = 0;
  while (src->Read(800, &b)) n += b.num_frames;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(n, 8000);
  EXPECT_GE(elapsed, 0.12);  // never faster than asked (a lower bound only; no upper bound on a busy machine)
}

TEST(FileSource, ClearErrorsForMismatches) {
  CaptureOptions o;
  o.file = MakeTestWav();
  o.num_channels = 6;
  ExpectOpenFails(o, "has 4 channels, expected 6");
  o.num_channels = 4;
  o.sample_rate_hz = 48000;
  ExpectOpenFails(o, "sample rate is 16000 Hz, expected 48000");
  o.file = TempPath("missing.wav");
  EXPECT_THROW(OpenAudioSource(o), AudioSourceError);
}

TEST(FileSource, RawFilesNeedAndUseTheGivenFormat) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/pocketsphinx_test/goforward.raw";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  CaptureOptions o;
  o.file = path;
  o.num_channels = 1;
  o.speed = 0;
  auto src = OpenAudioSource(o);
  AudioBlock b;
  int64_t n = 0;
  while (src->Read(1600, &b)) n += b.num_frames;
  EXPECT_NEAR(n / 16000.0, 2.8, 0.2);
}

TEST(SignalChecker, WarnsOnClippingAndSilence) {
  CaptureOptions o = TestWavAtSpeed(0);
  o.silence_warn_s = 0.25;
  auto src = OpenAudioSource(o);
  SignalChecker checker(o, 16000, 4);
  AudioBlock b;
  std::vector<std::string> all;
  while (src->Read(512, &b))
    for (auto& w : checker.Check(b)) all.push_back(w);
  bool clip = false, silent2 = false, silent_other = false;
  for (const auto& w : all) {
    clip |= w.find("clipped") != std::string::npos;
    silent2 |= w.find("channel 2 silent") != std::string::npos && w.find("all zeros") != std::string::npos;
    silent_other |= w.find("channel 0 silent") != std::string::npos || w.find("channel 3 silent") != std::string::npos;
  }
  EXPECT_TRUE(clip);
  EXPECT_TRUE(silent2);
  EXPECT_FALSE(silent_other);
  EXPECT_GT(checker.clipped_samples(), 4000);
  // A block with the wrong channel count is reported, not a crash.
  b.num_channels = 3;
  EXPECT_FALSE(checker.Check(b).empty());
}

TEST(AlsaSource, AbsentDeviceFailsClearly) {
  CaptureOptions o;
  o.source = "alsa";
  o.device = "hw:97,0";
  try {
    OpenAudioSource(o);
    FAIL() << "expected an error (no such sound card here)";
  } catch (const AudioSourceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ALSA device 'hw:97,0'"), std::string::npos) << what;
    EXPECT_NE(what.find("arecord -l"), std::string::npos) << what;
  }
}

TEST(OutputChannel, PerDeviceChannelNames) {
  EXPECT_EQ(OutputChannel("AUDIO", "kinect"), "AUDIO");
  EXPECT_EQ(OutputChannel("AUDIO_*", "hw:CARD=Array"), "AUDIO_HW_CARD_ARRAY");
}

}  // namespace
}  // namespace audio
}  // namespace sarmap
