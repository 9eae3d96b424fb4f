#include "mic_calibrate/calibration.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/robot_config.h"
#include "mic_calibrate/calibration_io.h"
#include "mic_calibrate/simulation.h"

namespace sarmap {
namespace mic_calibrate {
namespace {

SimScenario Grid(int rows, int cols) {
  SimScenario sc;
  sc.rows = rows;
  sc.cols = cols;
  return sc;
}

void Print(const char* name, const MonteCarloSummary& m) {
  printf("[ figures  ] %-14s runs %d: pos %.4f m, tau %.4f ms, delta %.4f us/s, residual rms "
         "%.4f ms, iterations %.1f\n",
         name, m.runs, m.mean.position_rms_m, m.mean.offset_rms_s * 1e3, m.mean.drift_rms * 1e6,
         m.mean_residual_rms_s * 1e3, m.mean_iterations);
}

// The summary's mean errors at or below the bounds (m, s, s/s).
void ExpectMeanAtMost(const MonteCarloSummary& m, double position_rms_m, double offset_rms_s,
                      double drift_rms) {
  EXPECT_LE(m.mean.position_rms_m, position_rms_m);
  EXPECT_LE(m.mean.offset_rms_s, offset_rms_s);
  EXPECT_LE(m.mean.drift_rms, drift_rms);
}

// Calibrate refuses the data as unobservable, with each of `phrases` in its message.
void ExpectUnobservable(const SimData& sim, const SolverOptions& o,
                        const std::vector<std::string>& phrases, const std::string& why) {
  try {
    Calibrate(sim.data, o);
    FAIL() << why;
  } catch (const UnobservableError& e) {
    for (const std::string& phrase : phrases)
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
  }
}

// Noise-free TDOAs: the estimate must be the truth (pins the model, the gauge and the units).
TEST(Calibration, NoiseFreeDataGiveTheTruth) {
  SimScenario sc = Grid(3, 3);
  sc.num_positions = 150;
  sc.noise_conservative_factor = std::numeric_limits<double>::infinity();
  sc.sample_rate_hz = 0;  // no quantisation
  const SimData sim = Simulate(sc, 7);
  SolverOptions o = SolverOptionsFor(sc, sim);
  o.tdoa_sigma_s = 1e-5;
  o.function_tolerance = 1e-14;
  o.parameter_tolerance = 1e-12;
  o.max_iterations = 200;
  const CalibrationResult r = Calibrate(sim.data, o);
  const Errors e = CompareToTruth(r, sim);
  EXPECT_LT(e.position_rms_m, 1e-5);
  EXPECT_LT(e.offset_rms_s, 1e-7);  // reached: 1.8e-8 s (solver tolerance, not the model)
  EXPECT_LT(e.drift_rms, 1e-9);      // reached: 2.4e-10
  EXPECT_LT(r.residual_rms_s, 1e-8);
  EXPECT_TRUE(r.has_covariance);
  // Gauge: mic 1 at the origin, mic 3 on +x, mic 4 with y > 0.
  EXPECT_EQ(r.mic_positions_m[0].norm(), 0.0);
  EXPECT_EQ(r.mic_positions_m[2].y(), 0.0);
  EXPECT_GT(r.mic_positions_m[2].x(), 0.0);
  EXPECT_GT(r.mic_positions_m[3].y(), 0.0);
  EXPECT_EQ(r.mic_position_cov[0].norm(), 0.0);
  EXPECT_EQ(r.mic_position_cov[2](1, 1), 0.0);
  EXPECT_GT(r.mic_position_cov[2](0, 0), 0.0);
}

// A solve stopped by max_iterations says so: converged false and a warning (the CLI exits 4);
// the same data solved to the end converge without that warning. Residuals larger than the
// stated TDOA sigma widen the covariance (variance factor).
TEST(Calibration, AnUnconvergedSolveIsMarkedUntrusted) {
  SimScenario sc = Grid(3, 3);
  sc.num_positions = 150;
  const SimData sim = Simulate(sc, 11);
  SolverOptions o = SolverOptionsFor(sc, sim);
  o.max_position_std_m = 1e9;
  o.max_offset_std_s = 1e9;
  const auto did_not_converge = [](const CalibrationResult& r) {
    for (const auto& w : r.warnings) {
      if (w.find("did not converge") != std::string::npos) return true;
    }
    return false;
  };
  o.max_iterations = 200;
  const CalibrationResult full = Calibrate(sim.data, o);
  EXPECT_TRUE(full.converged);
  EXPECT_FALSE(did_not_converge(full));
  EXPECT_GE(full.variance_factor, 1.0);
  o.max_iterations = 2;
  o.num_starts = 1;
  const CalibrationResult stopped = Calibrate(sim.data, o);
  EXPECT_FALSE(stopped.converged);
  EXPECT_TRUE(did_not_converge(stopped));
  // Stopped early, its residuals are far above the stated sigma: the std says so.
  EXPECT_GT(stopped.variance_factor, 1.0);
  EXPECT_GT(stopped.residual_rms_s, o.tdoa_sigma_s);
}

// Table 3.2 with Table 3.1 settings (fewer runs than the bench's 10; the thesis bound is the
// acceptance goal where we meet it over 10 runs, the reached figure where we do not).
TEST(Calibration, Table32Arrays) {
  // 3x2: the 10-run bench meets the thesis (0.085 m / 0.195 ms / 0.28 us/s); these 3 runs
  // (one bad geometry among them) reach 0.186 m / 0.40 ms / 0.24 us/s.
  const MonteCarloSummary m32 = RunMonteCarlo(Grid(3, 2), 3, 1);
  Print("3x2", m32);
  EXPECT_EQ(m32.failures, 0);
  ExpectMeanAtMost(m32, 0.2, 0.45e-3, 1.6446e-6);

  const MonteCarloSummary m33 = RunMonteCarlo(Grid(3, 3), 2, 1);
  Print("3x3", m33);
  EXPECT_EQ(m33.failures, 0);
  ExpectMeanAtMost(m33, 0.0335, 0.0812e-3, 0.6952e-6);

  // 4x4: thesis 0.0103 m / 0.0276 ms / 0.1936 us (met by the 10-run bench: 0.0078 / 0.0148 /
  // 0.168; this run 0.0060 / 0.0111 / 0.108).
  const MonteCarloSummary m44 = RunMonteCarlo(Grid(4, 4), 1, 1);
  Print("4x4", m44);
  EXPECT_EQ(m44.failures, 0);
  ExpectMeanAtMost(m44, 0.0103, 0.0276e-3, 0.1936e-6);
}

// Table 3.3: half and twice the positions (K = 160 / 640; met by the 10-run bench).
TEST(Calibration, Table33NumberOfPositions) {
  SimScenario half = Grid(3, 3), twice = Grid(3, 3);
  half.num_positions /= 2;
  twice.num_positions *= 2;
  const MonteCarloSummary mh = RunMonteCarlo(half, 2, 1);
  Print("3x3 half", mh);
  ExpectMeanAtMost(mh, 0.1480, 0.3038e-3, 2.4248e-6);
  const MonteCarloSummary mt = RunMonteCarlo(twice, 1, 1);
  Print("3x3 twice", mt);
  ExpectMeanAtMost(mt, 0.0106, 0.0239e-3, 0.1450e-6);
}

// Fig. 3.13: the same data solved without drift goes wrong (refused by the covariance check;
// with the check off, errors of metres and residuals far above the noise).
TEST(Calibration, WithoutDriftDiverges) {
  const SimScenario sc = Grid(3, 3);
  const SimData sim = Simulate(sc, 1);
  SolverOptions o = SolverOptionsFor(sc, sim);
  o.seed = 1001;
  const CalibrationResult with = Calibrate(sim.data, o);
  const Errors e_with = CompareToTruth(with, sim);
  o.estimate_drift = false;
  o.num_starts = 2;
  o.max_position_std_m = 1e9;
  o.max_offset_std_s = 1e9;
  const CalibrationResult without = Calibrate(sim.data, o);
  const Errors e_without = CompareToTruth(without, sim);
  printf("[ figures  ] with drift: pos %.4f m, residual rms %.4f ms; without: pos %.3f m, "
         "residual rms %.4f ms\n",
         e_with.position_rms_m, with.residual_rms_s * 1e3, e_without.position_rms_m,
         without.residual_rms_s * 1e3);
  EXPECT_GT(e_without.position_rms_m, 10 * e_with.position_rms_m);
  EXPECT_GT(e_without.position_rms_m, 0.3);
  EXPECT_GT(without.residual_rms_s, 3 * with.residual_rms_s);
}

TEST(Calibration, ThreeDimensionalArray3x3x2) {
  SimScenario sc = Grid(3, 3);
  sc.layers = 2;
  sc.num_positions = 200;
  const SimData sim = Simulate(sc, 3);
  SolverOptions o = SolverOptionsFor(sc, sim);
  o.seed = 3;
  const CalibrationResult r = Calibrate(sim.data, o);
  const Errors e = CompareToTruth(r, sim);
  printf("[ figures  ] 3x3x2: pos %.4f m, tau %.4f ms, delta %.4f us/s\n", e.position_rms_m,
         e.offset_rms_s * 1e3, e.drift_rms * 1e6);
  EXPECT_EQ(r.dim, 3);
  EXPECT_LT(e.position_rms_m, 0.06);
  EXPECT_LT(e.offset_rms_s, 0.1e-3);
  EXPECT_LT(e.drift_rms, 0.8e-6);
  // 3D gauge: mic 3 on +x, mic 7 in z = 0 with y > 0, mic 10 above.
  EXPECT_EQ(r.mic_positions_m[2].y(), 0.0);
  EXPECT_EQ(r.mic_positions_m[2].z(), 0.0);
  EXPECT_EQ(r.mic_positions_m[6].z(), 0.0);
  EXPECT_GT(r.mic_positions_m[6].y(), 0.0);
  EXPECT_GT(r.mic_positions_m[9].z(), 0.0);
}

// Table 3.4: linear 4-mic array of known spacing: offsets and drift only.
TEST(Calibration, LinearArrayTable34) {
  SimScenario sc;
  sc.linear = true;
  sc.spacing_m = 0.05;
  sc.tdoa_sigma_s = 3.33e-3;
  sc.num_positions = 180;
  const MonteCarloSummary m = RunMonteCarlo(sc, 4, 1);
  Print("linear 4", m);
  EXPECT_EQ(m.failures, 0);
  EXPECT_LT(m.mean.offset_rms_s, 0.5e-3);
  EXPECT_LT(m.mean.drift_rms, 8e-6);
}

TEST(Calibration, SynchronousArrayPositionsOnly) {
  SimScenario sc = Grid(3, 3);
  sc.max_offset_s = 0;
  sc.max_drift = 0;
  sc.num_positions = 150;
  const SimData sim = Simulate(sc, 5);
  SolverOptions o = SolverOptionsFor(sc, sim);
  o.synchronous = true;
  const CalibrationResult r = Calibrate(sim.data, o);
  const Errors e = CompareToTruth(r, sim);
  EXPECT_LT(e.position_rms_m, 0.03);
  for (double t : r.start_offsets_s) EXPECT_EQ(t, 0.0);
  const common::MicArrayOptions a = ToArrayOptions(r, o, "sync", 16000);
  EXPECT_TRUE(a.start_offsets_s.empty());
}

// Known geometry: positions held at the given ones (any frame: mic 1 is moved to the origin),
// only offsets and drifts (and the source) estimated. A 2D layout pins the clocks; a
// collinear one (Kinect-like) leaves the clock component proportional to the mic coordinate
// along the line nearly unobservable (far field it equals a shift of every cos(bearing)),
// so its errors are an order of magnitude larger (see README, end to end).
TEST(Calibration, KnownPositionsOffsetsAndDriftOnly) {
  for (int cols : {3, 4}) {
    SimScenario sc = cols == 3 ? Grid(3, 3) : Grid(1, 4);
    sc.num_positions = 200;
    const SimData sim = Simulate(sc, 3);
    SolverOptions o = SolverOptionsFor(sc, sim);
    o.known_positions = true;
    o.gauge_x_mic = 2;  // unused with known positions (they fix the frame)
    o.gauge_plane_mic = 3;
    EXPECT_THROW(Calibrate(sim.data, o), std::invalid_argument);  // positions not given
    InitialGuess g;
    for (const auto& p : sim.mic_positions_m) g.mic_positions_m.push_back(p + Eigen::Vector3d(1, 2, 0));
    const CalibrationResult r = Calibrate(sim.data, o, &g);
    const Errors e = CompareToTruth(r, sim);
    printf("[ figures  ] known positions (%s): tau %.4f ms, delta %.4f us/s\n",
           cols == 3 ? "3x3" : "linear 4", e.offset_rms_s * 1e3, e.drift_rms * 1e6);
    EXPECT_EQ(e.position_rms_m, 0.0);
    EXPECT_LT(e.offset_rms_s, cols == 3 ? 0.06e-3 : 0.4e-3);  // reached 0.044 / 0.334 ms
    EXPECT_LT(e.drift_rms, cols == 3 ? 1.0e-6 : 8e-6);  // reached 0.78 / 6.0 us/s (noise 0.111 ms)
  }
}

// Degenerate input: refused with an explanation of what is unobservable.
TEST(Calibration, StationarySourceIsRefused) {
  SimScenario sc = Grid(3, 3);
  sc.step_m = 0;  // the source never moves
  sc.num_positions = 100;
  const SimData sim = Simulate(sc, 2);
  const SolverOptions o = SolverOptionsFor(sc, sim);
  ExpectUnobservable(sim, o, {"did not move"}, "a source that never moves must be refused");
}

TEST(Calibration, TooFewPositionsAreRefused) {
  SimScenario sc = Grid(3, 3);
  sc.num_positions = 4;
  const SimData sim = Simulate(sc, 2);
  const SolverOptions o = SolverOptionsFor(sc, sim);
  ExpectUnobservable(sim, o, {"too few emissions", "need at least"},
                     "4 positions cannot determine 8 mics' positions, offsets and drifts");
  // Three microphones cannot locate a planar source from two TDOAs.
  SimScenario tiny = Grid(1, 3);
  const SimData sim3 = Simulate(tiny, 2);
  SolverOptions o3 = SolverOptionsFor(tiny, sim3);
  o3.gauge_plane_mic = 2;
  o3.gauge_x_mic = 3;
  EXPECT_THROW(Calibrate(sim3.data, o3), UnobservableError);
}

TEST(Calibration, NanTdoas) {
  SimScenario sc = Grid(3, 3);
  sc.num_positions = 200;
  SimData sim = Simulate(sc, 4);
  SolverOptions o = SolverOptionsFor(sc, sim);
  // A few missing values: left out, counted, still calibrated.
  for (int k = 0; k < 200; k += 10) sim.data.tdoa_s(k, k % 8) = std::nan("");
  const CalibrationResult r = Calibrate(sim.data, o);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("20 of 1600 TDOAs are missing"), std::string::npos) << r.warnings[0];
  EXPECT_LT(CompareToTruth(r, sim).position_rms_m, 0.06);
  // A microphone without any finite TDOA: refused, naming it.
  for (int k = 0; k < 200; ++k) sim.data.tdoa_s(k, 4) = std::nan("");
  ExpectUnobservable(sim, o, {"mic 6 has 0 finite TDOAs"}, "mic 6 without TDOAs must be refused");
}

TEST(Calibration, GaugeFrameOfRotatedPositions) {
  SimScenario sc = Grid(3, 3);
  sc.layers = 2;
  const SimData sim = Simulate(sc, 1);
  const Eigen::Matrix3d rot =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  std::vector<Eigen::Vector3d> moved;
  for (const auto& p : sim.mic_positions_m) moved.push_back(rot * p + Eigen::Vector3d(1, -2, 0.5));
  const auto back = ToGaugeFrame(moved, 3, sim.gauge_x, sim.gauge_plane, sim.gauge_z);
  for (size_t n = 0; n < back.size(); ++n) EXPECT_LT((back[n] - sim.mic_positions_m[n]).norm(), 1e-12);
  int gx = 0, gp = 0, gz = 0;
  ChooseGauge(18, 3, sim.mic_positions_m, &gx, &gp, &gz);
  // The thesis' 3D gauge: mic 3 on +x, mic 7 in the plane, mic 10 above.
  EXPECT_EQ(gx, 3);
  EXPECT_EQ(gp, 7);
  EXPECT_EQ(gz, 10);
}

TEST(Calibration, ArrayYamlLoadsWithLoadMicArray) {
  SimScenario sc = Grid(3, 2);
  const SimData sim = Simulate(sc, 1);
  SolverOptions o = SolverOptionsFor(sc, sim);
  const CalibrationResult r = Calibrate(sim.data, o);
  const common::MicArrayOptions a = ToArrayOptions(r, o, "test_array", 44100);
  const std::string path = ::testing::TempDir() + "/mic_calibrate_array.yaml";
  WriteArrayYaml(path, a, "test");
  const common::MicArrayOptions b = common::LoadMicArray(path);
  EXPECT_EQ(b.name, "test_array");
  EXPECT_EQ(b.geometry, "planar");
  ASSERT_EQ(b.num_mics(), 6);
  ASSERT_EQ(b.mic_position_std_m.size(), 6u);
  ASSERT_EQ(b.start_offsets_s.size(), 6u);
  ASSERT_EQ(b.clock_drift.size(), 6u);
  for (int n = 0; n < 6; ++n) {
    EXPECT_NEAR((b.mic_position(n) - r.mic_positions_m[n]).norm(), 0, 1e-5);
    EXPECT_NEAR(b.start_offsets_s[n], r.start_offsets_s[n], 1e-9);
    EXPECT_NEAR(b.clock_drift[n], r.clock_drift[n], 1e-11);
  }
  EXPECT_GT(b.mic_position_std_m[1], 0.0);
}

// The analytic TDOA Jacobian (used in the solve) must match the autodiff'd functor.
TEST(Calibration, AnalyticJacobianMatchesAutodiff) {
  EXPECT_TRUE(internal_testing::CheckTdoaJacobian(2));
  EXPECT_TRUE(internal_testing::CheckTdoaJacobian(3));
}

// A plane microphone on the x axis cannot fix the rotation about x: the null space is found
// at the solution and explained.
TEST(Calibration, CollinearGaugeIsRefused) {
  SimScenario sc;
  sc.layers = 2;
  sc.num_positions = 120;
  const SimData sim = Simulate(sc, 8);
  SolverOptions o = SolverOptionsFor(sc, sim);
  o.gauge_plane_mic = 2;  // (0.5, 0, 0): on the line of mic 1 and mic 3
  o.num_starts = 2;
  ExpectUnobservable(sim, o, {"plane 2"}, "a collinear gauge must be refused");
}
}  // namespace
}  // namespace mic_calibrate
}  // namespace sarmap
