#include "sound_localisation/audio_intake.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <random>

#include "sound_localisation/localiser.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/doa_evaluation.h"

namespace sarmap {
namespace sound {
namespace {

using Verdict = AudioIntake::Verdict;

TEST(AudioIntake, TakesOnlyTheConfiguredDeviceAndReportsEachOtherOnce) {
  AudioIntake intake("respeaker", 16000, 0.25);
  // Another device first: dropped, never locked onto.
  AudioIntake::Decision d = intake.Offer("rogue", 0, 512);
  EXPECT_EQ(d.verdict, Verdict::kOtherDevice);
  EXPECT_NE(d.report.find("'rogue'"), std::string::npos) << d.report;
  EXPECT_NE(d.report.find("'respeaker'"), std::string::npos) << d.report;
  EXPECT_EQ(intake.Offer("respeaker", 1000, 512).verdict, Verdict::kContinue);
  // The same other device again, interleaved: dropped and counted, reported no more.
  for (int i = 0; i < 10; ++i) {
    d = intake.Offer("rogue", 512 * (i + 1), 512);
    EXPECT_EQ(d.verdict, Verdict::kOtherDevice);
    EXPECT_TRUE(d.report.empty()) << d.report;
    EXPECT_EQ(intake.Offer("respeaker", 1512 + 512 * i, 512).verdict, Verdict::kContinue);
  }
  EXPECT_EQ(intake.device(), "respeaker");
  EXPECT_EQ(intake.other_device_blocks(), 11);
  EXPECT_EQ(intake.other_devices(), 1);
  EXPECT_EQ(intake.blocks(), 11);
  EXPECT_NE(intake.Summary().find("other devices 1 (11 blocks)"), std::string::npos)
      << intake.Summary();
}

TEST(AudioIntake, WithoutAConfiguredDeviceSaysWhichItTookAndReportsASecond) {
  AudioIntake intake("", 16000, 0.25);
  AudioIntake::Decision d = intake.Offer("card0", 0, 512);
  EXPECT_EQ(d.verdict, Verdict::kContinue);
  EXPECT_NE(d.report.find("'card0', the first heard"), std::string::npos) << d.report;
  d = intake.Offer("card1", 0, 512);
  EXPECT_EQ(d.verdict, Verdict::kOtherDevice);
  EXPECT_NE(d.report.find("second audio device 'card1'"), std::string::npos) << d.report;
  EXPECT_TRUE(intake.Offer("card0", 512, 512).report.empty());
  // A flood of new device ids: each of the first kMaxNamedDevices reported once, then one line.
  int reports = 0;
  for (int i = 0; i < 1000; ++i) {
    if (!intake.Offer("flood" + std::to_string(i), 0, 512).report.empty()) ++reports;
  }
  EXPECT_EQ(reports, static_cast<int>(AudioIntake::kMaxNamedDevices));  // card1 was the first
  EXPECT_EQ(intake.other_devices(), static_cast<int64_t>(AudioIntake::kMaxNamedDevices));
  EXPECT_EQ(intake.other_device_blocks(), 1001);
  EXPECT_EQ(intake.Offer("card0", 1024, 512).verdict, Verdict::kContinue);
}

TEST(AudioIntake, BridgesShortGapsRestartsOnDiscontinuitiesDropsRepeats) {
  AudioIntake intake("mic", 16000, 0.25);  // 4000 samples bridged
  EXPECT_EQ(intake.Offer("mic", 0, 512).verdict, Verdict::kContinue);
  AudioIntake::Decision d = intake.Offer("mic", 1024, 512);  // one block lost
  EXPECT_EQ(d.verdict, Verdict::kBridge);
  EXPECT_EQ(d.gap_samples, 512);
  d = intake.Offer("mic", 1536 + 3 * 512, 512);  // three lost
  EXPECT_EQ(d.verdict, Verdict::kBridge);
  EXPECT_EQ(d.gap_samples, 1536);
  EXPECT_EQ(intake.Offer("mic", 3072, 512).verdict, Verdict::kStale);  // a repeat
  EXPECT_EQ(intake.Offer("mic", 3584, 512).verdict, Verdict::kContinue);
  d = intake.Offer("mic", 4096 + 16000, 512);  // a second lost: a real discontinuity
  EXPECT_EQ(d.verdict, Verdict::kRestart);
  EXPECT_EQ(d.gap_samples, 16000);
  EXPECT_EQ(intake.Offer("mic", 0, 512).verdict, Verdict::kRestart);  // the device reopened
  EXPECT_EQ(intake.Offer("mic", 512, 512).verdict, Verdict::kContinue);
  // Counters near the int64 limits are dropped, not overflowed.
  EXPECT_EQ(intake.Offer("mic", LLONG_MAX - 10, 512).verdict, Verdict::kStale);
  EXPECT_EQ(intake.Offer("mic", LLONG_MIN, 512).verdict, Verdict::kStale);
  EXPECT_EQ(intake.Offer("mic", 1024, 512).verdict, Verdict::kContinue);
  EXPECT_EQ(intake.bridged_gaps(), 2);
  EXPECT_EQ(intake.bridged_samples(), 2048);
  EXPECT_EQ(intake.restarts(), 2);
  EXPECT_EQ(intake.stale_blocks(), 3);
  EXPECT_THROW(AudioIntake("mic", 0, 0.25), std::invalid_argument);
  EXPECT_THROW(AudioIntake("mic", 16000, -1), std::invalid_argument);
}

// A talker-like source (noise bursts, 0.3 s on, 0.2 s off) at azimuth 60 deg on the ReSpeaker,
// streamed in the simulator's 512-sample blocks of which 10 % are lost at random (as at 10 %
// datagram loss). Through the intake the gaps are bridged: no restart, the localiser's time
// line stays the device's, and the directions come out as without loss.
TEST(AudioIntake, TenPercentBlockLossIsBridgedAndDirectionsGoOn) {
  const ArrayGeometry g = testing_util::LoadArray("respeaker4");
  const double fs = g.sample_rate_hz;
  const size_t n = static_cast<size_t>(8.0 * fs);
  std::vector<float> s = testing_util::WhiteNoise(n, 3);
  for (size_t i = 0; i < n; ++i) {
    if (std::fmod(i / fs, 0.5) > 0.3) s[i] = 0;
  }
  const double truth_az = DegToRad(60);
  const Eigen::VectorXd delays =
      g.Delays(Eigen::Vector3d(std::cos(truth_az), std::sin(truth_az), 0.0));
  std::vector<std::vector<float>> mics(g.num_mics(), std::vector<float>(n, 0.0f));
  const auto noise = testing_util::WhiteNoise(n * g.num_mics(), 5);
  for (int m = 0; m < g.num_mics(); ++m) {
    testing_util::AddDelayed(s, 20 + delays[m] * fs, 1.0, &mics[m]);
    for (size_t i = 0; i < n; ++i) mics[m][i] += 0.01f * noise[m * n + i];
  }
  int channels = 0;
  for (int c : g.channel_map) channels = std::max(channels, c + 1);
  std::vector<int16_t> interleaved(n * channels, 0);
  for (int m = 0; m < g.num_mics(); ++m) {
    for (size_t i = 0; i < n; ++i) {
      const float v = std::clamp(mics[m][i] * 4000.0f, -32767.0f, 32767.0f);
      interleaved[i * channels + g.channel_map[m]] = static_cast<int16_t>(v);
    }
  }

  constexpr int kBlock = 512;
  const int blocks = static_cast<int>(n / kBlock);
  std::mt19937 rng(17);
  std::bernoulli_distribution lost(0.10);
  std::vector<bool> keep(blocks);
  int kept = 0;
  for (int b = 0; b < blocks; ++b) kept += (keep[b] = b == 0 || !lost(rng));

  LocaliserOptions o;
  o.search = "azimuth";
  o.max_sources = 1;
  struct Run {
    int with_direction = 0;
    double median_error_deg = 180;
    int64_t last_end_sample = 0, restarts = 0;
  };
  // lossy: drop blocks; bridge: through the intake (otherwise every gap restarts the analysis).
  const auto run = [&](bool lossy, bool bridge) {
    Localiser localiser(g, o, nullptr);
    AudioIntake intake("respeaker4", static_cast<int>(fs), bridge ? 0.25 : 0.0);
    std::vector<LocaliserOutput> outs;
    for (int b = 0; b < blocks; ++b) {
      if (lossy && !keep[b]) continue;
      const AudioIntake::Decision d = intake.Offer("respeaker4", int64_t{b} * kBlock, kBlock);
      if (d.verdict == Verdict::kBridge) localiser.SkipSamples(d.gap_samples);
      if (d.verdict == Verdict::kRestart) localiser.ResetStream();
      localiser.Push(&interleaved[static_cast<size_t>(b) * kBlock * channels], kBlock, channels,
                     &outs);
    }
    Run r;
    std::vector<double> errors;
    for (const auto& out : outs) {
      r.last_end_sample = out.end_sample;
      if (out.directions.empty()) continue;
      ++r.with_direction;
      errors.push_back(std::abs(
          RadToDeg(std::remainder(out.directions[0].direction.azimuth_rad - truth_az, 2 * M_PI))));
    }
    if (!errors.empty()) r.median_error_deg = Median(errors);
    r.restarts = intake.restarts();
    EXPECT_EQ(localiser.samples_seen(),
              lossy && !bridge ? int64_t{kept} * kBlock : int64_t{blocks} * kBlock);
    return r;
  };
  const Run clean = run(false, true), bridged = run(true, true), restarted = run(true, false);
  std::printf(
      "%d of %d blocks kept; outputs with a direction / median azimuth error / restarts:\n"
      "  no loss %d / %.2f deg / %lld, bridged %d / %.2f deg / %lld, restart per gap %d / "
      "%.2f deg / %lld\n",
      kept, blocks, clean.with_direction, clean.median_error_deg,
      static_cast<long long>(clean.restarts), bridged.with_direction, bridged.median_error_deg,
      static_cast<long long>(bridged.restarts), restarted.with_direction,
      restarted.median_error_deg, static_cast<long long>(restarted.restarts));
  ASSERT_LT(kept, blocks * 95 / 100) << "the stream must lose blocks";
  EXPECT_GT(restarted.restarts, 10);  // what the loss did without bridging
  EXPECT_EQ(bridged.restarts, 0);
  EXPECT_GE(bridged.with_direction, clean.with_direction * 8 / 10);
  EXPECT_LT(bridged.median_error_deg, 3.0);
  // The time line is the device's: the last output ends where the lossless run's does.
  EXPECT_NEAR(static_cast<double>(bridged.last_end_sample),
              static_cast<double>(clean.last_end_sample), kBlock * 2);
}

TEST(AudioIntake, CheckAudioBlockNamesWhatIsWrongWithABlock) {
  AudioBlockFormat block;
  block.device_id = "card\n1";
  block.sample_rate_hz = 16000;
  block.num_channels = 6;
  block.num_samples = 256;
  block.num_values = 6 * 256;
  EXPECT_EQ(CheckAudioBlock(block, 16000, 6, "respeaker"), "");
  EXPECT_EQ(CheckAudioBlock(block, 16000, 4, "respeaker"), "");
  const std::string rate = CheckAudioBlock(block, 48000, 6, "respeaker");
  EXPECT_NE(rate.find("sample-rate mismatch: device 'card\\x0a1' is 16000 Hz, array 'respeaker' "
                      "expects 48000 Hz"),
            std::string::npos)
      << rate;
  const std::string channels = CheckAudioBlock(block, 16000, 8, "cube8");
  EXPECT_NE(channels.find("has 6 channels, array 'cube8' needs 8"), std::string::npos) << channels;
  block.num_values -= 1;
  EXPECT_NE(CheckAudioBlock(block, 16000, 6, "respeaker").find("malformed"), std::string::npos);
  block.num_values += 1;
  block.int16 = false;
  EXPECT_NE(CheckAudioBlock(block, 16000, 6, "respeaker").find("malformed"), std::string::npos);
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
