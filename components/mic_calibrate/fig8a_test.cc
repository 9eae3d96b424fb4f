// Real data: shared/data/audio/calibration/fig8a_* (a real asynchronous 6-mic array, one
// USB sound card per mic, TDOAs at 44.1 kHz of a hand-held chirping source moved in a loop
// around it; measured mic and source positions).
#include <cmath>
#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "mic_calibrate/calibration.h"
#include "mic_calibrate/calibration_io.h"

namespace sarmap {
namespace mic_calibrate {
namespace {

const std::string kDir = std::string(SARMAP_DATA_DIR) + "/audio/calibration/";

bool HaveData() { return std::ifstream(kDir + "fig8a_tdoa.csv").good(); }

struct Fig8a {
  TdoaCsv tdoa;
  MicsCsv mics;
  SolverOptions options;
  InitialGuess guess;
};

// The documented real-data setup (README): 3d, gauge from the measured layout (mic 2 on +x,
// mic 3 y > 0, mic 5 z > 0), TDOA sigma and motion prior from the files, first start from
// the paper's initial guess, the other starts random.
Fig8a Load() {
  Fig8a f;
  f.tdoa = ReadTdoaCsv(kDir + "fig8a_tdoa.csv", 0.5);
  ReadMotionCsv(kDir + "fig8a_odometry.csv", &f.tdoa.data);
  f.mics = ReadMicsCsv(kDir + "fig8a_mics.csv");
  f.options.geometry = "3d";
  f.options.speed_of_sound_mps = 340;  // the data's model (compute_global_error.m)
  ChooseGauge(6, 3, f.mics.truth_m, &f.options.gauge_x_mic, &f.options.gauge_plane_mic,
              &f.options.gauge_z_mic);
  f.guess.mic_positions_m = ToGaugeFrame(f.mics.init_m, 3, f.options.gauge_x_mic,
                                         f.options.gauge_plane_mic, f.options.gauge_z_mic);
  return f;
}

TEST(Fig8aRealData, LoadsAsDocumented) {
  if (!HaveData()) GTEST_SKIP() << "shared data missing: " << kDir;
  const Fig8a f = Load();
  EXPECT_EQ(f.tdoa.data.num_mics, 6);
  EXPECT_EQ(f.tdoa.data.num_emissions(), 97);
  EXPECT_NEAR(f.tdoa.data.sigma_s[0], 1.0 / 3000, 1e-9);  // info 9e6
  EXPECT_NEAR(f.tdoa.data.motion_sigma_m[0].x(), 0.5, 1e-12);  // info 4
  EXPECT_EQ(f.options.gauge_x_mic, 2);
  EXPECT_EQ(f.options.gauge_plane_mic, 3);
  EXPECT_EQ(f.options.gauge_z_mic, 5);
}

// With the default refusal thresholds the tool refuses: the loop lies in the plane of mics
// 1-4, so the data hardly constrain the geometry (marginal position std of metres).
TEST(Fig8aRealData, DefaultRefusesAndSaysWhy) {
  if (!HaveData()) GTEST_SKIP() << "shared data missing: " << kDir;
  const Fig8a f = Load();
  try {
    Calibrate(f.tdoa.data, f.options, &f.guess);
    FAIL() << "expected a refusal";
  } catch (const UnobservableError& e) {
    printf("[ figures  ] refusal: %s\n", e.what());
    EXPECT_NE(std::string(e.what()).find("position std"), std::string::npos);
  }
}

// Report mode (refusal off): residual std goal <= 0.3 ms (met); the mic-position RMS against
// the measured positions is pinned at what we reach (README: not close to the thesis' 0.03 m).
TEST(Fig8aRealData, ResidualsAndPositionError) {
  if (!HaveData()) GTEST_SKIP() << "shared data missing: " << kDir;
  Fig8a f = Load();
  f.options.max_position_std_m = 1e9;
  f.options.max_offset_std_s = 1e9;
  const CalibrationResult r = Calibrate(f.tdoa.data, f.options, &f.guess);
  const TruthComparison c = CompareWithNominal(r, f.mics.truth_m, f.tdoa.source_truth_m);
  printf("[ figures  ] fig8a: residual std %.4f ms (rms %.4f, max %.4f), mic-position RMS %.4f m, "
         "source RMS %.4f m, %zu starts, %d iterations\n",
         r.residual_std_s * 1e3, r.residual_rms_s * 1e3, r.residual_max_abs_s * 1e3,
         c.position_rms_m, c.source_rms_m, r.starts.size(), r.total_iterations);
  ASSERT_TRUE(c.available);
  EXPECT_LE(r.residual_std_s, 0.3e-3);
  EXPECT_LT(c.position_rms_m, 0.7);
  EXPECT_GT(c.position_rms_m, 0.0);
}

// Prints the figures of the calibration `what` and checks them: a residual std of at most
// 0.3 ms, mic positions within `max_position_rms_m` and sources within 0.25 m (RMS).
void PrintAndCheckFigures(const char* what, const CalibrationResult& r, const TruthComparison& c,
                          double max_position_rms_m) {
  printf(
      "[ figures  ] fig8a %s: residual std %.4f ms, mic-position RMS %.4f m, source RMS %.4f m\n",
      what, r.residual_std_s * 1e3, c.position_rms_m, c.source_rms_m);
  EXPECT_LE(r.residual_std_s, 0.3e-3);
  EXPECT_LT(c.position_rms_m, max_position_rms_m);
  EXPECT_LT(c.source_rms_m, 0.25);
}

// Mics 1-4 are coplanar with the source loop: solved as a planar 4-mic array (the default
// planar configuration, random starts only) the geometry is much better determined.
TEST(Fig8aRealData, CoplanarMicsAsPlanarArray) {
  if (!HaveData()) GTEST_SKIP() << "shared data missing: " << kDir;
  const Fig8a f = Load();
  const TdoaData d = SelectMics(f.tdoa.data, {1, 2, 3, 4});
  SolverOptions o;
  o.geometry = "planar";
  o.speed_of_sound_mps = 340;
  const std::vector<Eigen::Vector3d> truth(f.mics.truth_m.begin(), f.mics.truth_m.begin() + 4);
  ChooseGauge(4, 2, truth, &o.gauge_x_mic, &o.gauge_plane_mic, &o.gauge_z_mic);
  const CalibrationResult r = Calibrate(d, o);
  const TruthComparison c = CompareWithNominal(r, truth, f.tdoa.source_truth_m);
  PrintAndCheckFigures("mics 1-4 planar", r, c, 0.15);
}

// What the known layout can legitimately add: the gauge mics 1, 2, 3 span the horizontal
// plane, the source was carried in that plane (sources_in_gauge_plane) and the mic heights
// were measured (0 for mics 1-4, 0.4 m for 5-6): a height prior of 0.02 m. Then all six
// positions are determined (marginal std <= 0.25 m, accepted by the default refusal
// thresholds) and within 0.021 m RMS of the measured ones (thesis: 0.0288 m for its 2x3).
TEST(Fig8aRealData, KnownHeightsAndSourcePlane) {
  if (!HaveData()) GTEST_SKIP() << "shared data missing: " << kDir;
  Fig8a f = Load();
  f.options.sources_in_gauge_plane = true;
  f.options.height_prior_sigma_m = 0.02;
  for (const auto& p : ToGaugeFrame(f.mics.truth_m, 3, f.options.gauge_x_mic,
                                    f.options.gauge_plane_mic, f.options.gauge_z_mic)) {
    f.options.mic_heights_m.push_back(p.z());
  }
  const CalibrationResult r = Calibrate(f.tdoa.data, f.options, &f.guess);
  const TruthComparison c = CompareWithNominal(r, f.mics.truth_m, f.tdoa.source_truth_m);
  PrintAndCheckFigures("known heights (0.02 m) + source plane", r, c, 0.03);
  // Without the height prior the source plane alone leaves mic 4's height unobservable.
  f.options.height_prior_sigma_m = 0;
  EXPECT_THROW(Calibrate(f.tdoa.data, f.options, &f.guess), UnobservableError);
}

}  // namespace
}  // namespace mic_calibrate
}  // namespace sarmap
