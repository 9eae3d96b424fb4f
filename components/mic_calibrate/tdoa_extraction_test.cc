#include "mic_calibrate/tdoa_extraction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>

#include "common/robot_config.h"
#include "mic_calibrate/calibration.h"
#include "mic_calibrate/lcm_audio_log.h"
#include "mic_calibrate/simulation.h"

namespace sarmap {
namespace mic_calibrate {
namespace {

// A 3x2 asynchronous array (0.5 m), offsets up to 50 ms, drifts up to 100 us/s, a source
// looping around it emitting a 20 ms chirp every 0.3 s.
struct Scene {
  SimData sim;
  Recording rec;
  ChirpSynthesis synth;
};

Scene MakeScene(int positions, double fs) {
  SimScenario sc;
  sc.rows = 3;
  sc.cols = 2;
  sc.num_positions = positions;
  sc.dt_s = 0.3;
  sc.max_offset_s = 0.05;
  Scene s;
  s.sim = Simulate(sc, 11);
  s.synth.sample_rate_hz = fs;
  s.synth.speed_of_sound_mps = sc.speed_of_sound_mps;
  s.rec = SynthesiseChirps(s.sim.mic_positions_m, s.sim.start_offsets_s, s.sim.clock_drift,
                           s.sim.source_positions_m, s.sim.data.times_s, s.synth, 5);
  return s;
}

// Model TDOA of mic n (0-based) at emission k, as the calibration defines it.
double ModelTdoa(const SimData& sim, int k, int n, double c) {
  const Eigen::Vector3d& src = sim.source_positions_m[k];
  const double geo = ((sim.mic_positions_m[n] - src).norm() - (sim.mic_positions_m[0] - src).norm()) / c;
  const double arrival = sim.data.times_s[k] + (sim.mic_positions_m[n] - src).norm() / c;
  return geo + sim.start_offsets_s[n] + arrival * sim.clock_drift[n];
}

double TdoaRmsError(const TdoaData& d, const SimData& sim, double c) {
  EXPECT_EQ(d.num_emissions(), sim.data.num_emissions());
  double s2 = 0;
  int cnt = 0;
  for (int k = 0; k < std::min(d.num_emissions(), sim.data.num_emissions()); ++k) {
    for (int n = 1; n < d.num_mics; ++n) {
      if (!std::isfinite(d.tdoa_s(k, n - 1))) continue;
      s2 += std::pow(d.tdoa_s(k, n - 1) - ModelTdoa(sim, k, n, c), 2);
      ++cnt;
    }
  }
  return std::sqrt(s2 / std::max(cnt, 1));
}

TEST(TdoaExtraction, GccPhatAndMatchedFilterAreSubSample) {
  const Scene s = MakeScene(30, 44100);
  for (const char* method : {"gcc_phat", "matched"}) {
    ExtractionOptions o;
    o.method = method;
    ExtractionStats st;
    const TdoaData d = ExtractTdoas(s.rec, o, &st);
    EXPECT_EQ(st.events, 30) << method;
    EXPECT_EQ(st.missing, 0) << method;
    const double err = TdoaRmsError(d, s.sim, s.synth.speed_of_sound_mps);
    printf("[ figures  ] %s TDOA rms error %.4f ms (1 sample = %.4f ms)\n", method, err * 1e3,
           1e3 / 44100);
    EXPECT_LT(err, 0.25 / 44100) << method;  // well below one sample
    // Emission times on the reference clock.
    for (int k = 0; k < d.num_emissions(); ++k) EXPECT_NEAR(d.times_s[k], s.sim.data.times_s[k], 0.01);
  }
}

TEST(TdoaExtraction, WavRoundTrip) {
  const Scene s = MakeScene(10, 16000);
  const std::string path = ::testing::TempDir() + "/mic_calibrate_test.wav";
  WriteWav(path, s.rec);
  const Recording back = ReadWav(path);
  ASSERT_EQ(back.channels.size(), 6u);
  EXPECT_EQ(back.sample_rate_hz, 16000);
  const TdoaData a = ExtractTdoas(s.rec, ExtractionOptions(), nullptr);
  const TdoaData b = ExtractTdoas(back, ExtractionOptions(), nullptr);
  ASSERT_EQ(a.num_emissions(), b.num_emissions());
  EXPECT_LT((a.tdoa_s - b.tdoa_s).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_THROW(ReadWav("/nonexistent.wav"), std::runtime_error);
}

// Each sound card is its own AUDIO_* channel with its own sample counter; card 4 is logged
// with a start utime 12.5 ms late, which the reader must carry into the alignment.
TEST(TdoaExtraction, LcmLogWithOneChannelPerCard) {
  Scene s = MakeScene(12, 16000);
  Recording rec = s.rec;
  rec.channel_start_s.assign(6, 0.0);
  rec.channel_start_s[3] = 0.0125;  // the utime claims card 4 started 12.5 ms later
  const std::string path = ::testing::TempDir() + "/mic_calibrate_test.lcmlog";
  WriteLcmAudioLog(path, rec, {{0}, {1}, {2}, {3}, {4}, {5}}, 1700000000000000LL, 512);
  LcmAudioLogStats st;
  const Recording back = ReadLcmAudioLog(path, "AUDIO", &st);
  EXPECT_EQ(st.devices, 6);
  EXPECT_EQ(st.bad_frames, 0);
  ASSERT_EQ(back.channels.size(), 6u);
  EXPECT_NEAR(back.channel_start_s[3], 0.0125, 1e-6);
  const TdoaData d = ExtractTdoas(back, ExtractionOptions(), nullptr);
  // Card 4's samples are the same as in the WAV case but its clock is declared 12.5 ms later:
  // its TDOA is 12.5 ms larger than the model's (the start offset absorbs it).
  ASSERT_EQ(d.num_emissions(), 12);
  for (int k = 0; k < 12; ++k) {
    EXPECT_NEAR(d.tdoa_s(k, 2) - ModelTdoa(s.sim, k, 3, 340), 0.0125, 0.3 / 16000) << k;
    EXPECT_NEAR(d.tdoa_s(k, 0), ModelTdoa(s.sim, k, 1, 340), 0.3 / 16000) << k;
  }
  EXPECT_THROW(ReadLcmAudioLog(path, "NO_SUCH_CHANNEL", nullptr), std::runtime_error);

  // A log cut off mid-event (a recorder killed): what precedes the cut is read, and the cut is
  // a warning rather than the end of the calibration.
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string cut = ::testing::TempDir() + "/mic_calibrate_cut.lcmlog";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() - 300);
  LcmAudioLogStats cut_stats;
  const Recording partial = ReadLcmAudioLog(cut, "AUDIO", &cut_stats);
  EXPECT_EQ(cut_stats.frames, st.frames - 1);
  EXPECT_EQ(partial.channels.size(), 6u);
  ASSERT_FALSE(cut_stats.warnings.empty());
  EXPECT_NE(cut_stats.warnings.front().find("the log breaks at byte"), std::string::npos)
      << cut_stats.warnings.front();
}

// Audio to array: synthesised recording -> TDOAs -> calibration.
TEST(TdoaExtraction, RecordingToCalibration) {
  const Scene s = MakeScene(250, 16000);
  const TdoaData d = ExtractTdoas(s.rec, ExtractionOptions(), nullptr);
  ASSERT_EQ(d.num_emissions(), 250);
  SimScenario sc;
  sc.rows = 3;
  sc.cols = 2;
  SolverOptions o = SolverOptionsFor(sc, s.sim);
  o.speed_of_sound_mps = 340;
  o.tdoa_sigma_s = 0.05e-3;
  const CalibrationResult r = Calibrate(d, o);
  const Errors e = CompareToTruth(r, s.sim);
  printf("[ figures  ] audio -> calibration: pos %.4f m, tau %.4f ms, delta %.4f us/s, residual "
         "std %.4f ms\n",
         e.position_rms_m, e.offset_rms_s * 1e3, e.drift_rms * 1e6, r.residual_std_s * 1e3);
  EXPECT_LT(e.position_rms_m, 0.02);
  EXPECT_LT(e.offset_rms_s, 0.05e-3);
  EXPECT_LT(r.residual_std_s, 0.05e-3);
}

// The CLI end to end on an LCM log with one AUDIO_* channel per sound card: the YAML it
// writes loads with LoadMicArray() and holds the array.
TEST(TdoaExtraction, CliOnOneCardPerChannelLog) {
  const Scene s = MakeScene(250, 16000);
  const std::string dir = ::testing::TempDir();
  const std::string log = dir + "/mic_calibrate_cli.lcmlog", yaml = dir + "/mic_calibrate_cli.yaml";
  WriteLcmAudioLog(log, s.rec, {{0}, {1}, {2}, {3}, {4}, {5}}, 1700000000000000LL, 1024);
  const std::string cmd = std::string(SARMAP_BIN_DIR) + "/sarmap-mic-calibrate " + log +
                          " --output " + yaml + " --report " + dir +
                          "/mic_calibrate_cli --quiet --set array_name=cards";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const common::MicArrayOptions a = common::LoadMicArray(yaml);
  EXPECT_EQ(a.name, "cards");
  EXPECT_EQ(a.sample_rate_hz, 16000);
  ASSERT_EQ(a.num_mics(), 6);
  double s2 = 0;
  for (int n = 1; n < 6; ++n) {
    s2 += (a.mic_position(n) - s.sim.mic_positions_m[n]).squaredNorm();
    EXPECT_NEAR(a.start_offsets_s[n], s.sim.start_offsets_s[n], 1e-4) << n;
    EXPECT_NEAR(a.clock_drift[n], s.sim.clock_drift[n], 1e-6) << n;
  }
  printf("[ figures  ] CLI on a 6-card LCM log: mic-position RMS %.4f m\n", std::sqrt(s2 / 5));
  EXPECT_LT(std::sqrt(s2 / 5), 0.02);
}

}  // namespace
}  // namespace mic_calibrate
}  // namespace sarmap
