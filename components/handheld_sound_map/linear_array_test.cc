#include "handheld_sound_map/linear_array.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <random>

namespace sarmap {
namespace sound_map {
namespace {

// (5.19): every hypothesis lies on the observed cone, and a hypothesis point seen from the
// anchor pose gives back the observed beta.
TEST(LinearArray, HypothesesLieOnTheObservedCone) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(1, 2, 0.5);
  MultiHypothesisOptions o;
  MultiHypothesisSource src(o, pose, 0.4, 0.01);
  ASSERT_EQ(src.hypotheses().size(), 10u);
  for (const auto& h : src.hypotheses()) {
    EXPECT_NEAR(LinearArrayBeta(pose, HypothesisPoint(src.axis(), h.s)), 0.4, 1e-9);
  }
}

// One source, noise-free observations from a rich trajectory: hypotheses are pruned and
// the survivors converge on the source.
TEST(LinearArray, MultiHypothesisConvergesWithParallax) {
  const Eigen::Vector3d truth(2.0, 1.0, 0.7);
  MultiHypothesisOptions o;
  std::unique_ptr<MultiHypothesisSource> src;
  for (int k = 0; k < 200 && !(src && src->converged()); ++k) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    const double a = 0.03 * k;
    pose.linear() = Eigen::AngleAxisd(0.5 * std::sin(a), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.translation() = Eigen::Vector3d(0.5 * std::sin(2 * a), 0.05 * k - 2, 0.5 * std::sin(3 * a));
    const double beta = LinearArrayBeta(pose, truth);
    if (!src) src = std::make_unique<MultiHypothesisSource>(o, pose, beta, 1e-4);
    else src->Update(pose, beta, 1e-4);
  }
  ASSERT_TRUE(src->converged());
  EXPECT_LT(src->alive(), 10);
  EXPECT_LT((src->MeanPoint() - truth).norm(), 0.3);
}

// A cone seeded from a wrong first DOA: the source's later DOAs, all from one pose, fit no
// hypothesis. Every survivor then fails the chi-square test; the source is Failed (to be
// started again) and never converged, however linear its hypotheses look.
TEST(LinearArray, AConeSeededFromAWrongDoaFails) {
  MultiHypothesisOptions o;
  const Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  MultiHypothesisSource src(o, pose, 0.6, 1e-4);  // 34 deg
  EXPECT_FALSE(src.Failed());
  for (int k = 0; k < 10; ++k) src.Update(pose, -0.2, 1e-4);  // -11 deg from the same place
  EXPECT_GE(src.alive(), 1);
  EXPECT_TRUE(src.Failed());
  EXPECT_FALSE(src.converged());
}

// Real data: the GP sensor model fitted on the thesis' 370 SRP-PHAT calibration pairs of a
// real linear array corrects the bias and reports larger noise towards endfire.
TEST(GpDoaModel, RealCalibrationData) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/ssm/gp_doa_calibration.csv";
  if (!std::ifstream(path)) GTEST_SKIP() << "shared data missing: " << path;
  auto gp = GpDoaModel::FitCsvDegrees(path);
  std::ifstream in(path);
  std::string line;
  double raw_sq = 0, gp_sq = 0;
  int n = 0;
  while (std::getline(in, line)) {
    double a, b;
    if (sscanf(line.c_str(), "%lf,%lf", &a, &b) != 2) continue;
    double m, v;
    gp->Predict(a * M_PI / 180, &m, &v);
    raw_sq += std::pow(a - b, 2);
    gp_sq += std::pow(m * 180 / M_PI - b, 2);
    ++n;
  }
  ASSERT_EQ(n, 370);
  const double raw_rms = std::sqrt(raw_sq / n), gp_rms = std::sqrt(gp_sq / n);
  printf("raw RMS %.2f deg, GP RMS %.2f deg, hyper l=%.2f sf=%.2f sn=%.2f\n", raw_rms, gp_rms,
         gp->hyper().length_rad, gp->hyper().sigma_f_rad, gp->hyper().sigma_n_rad);
  EXPECT_NEAR(raw_rms, 11.9, 0.2);  // README of the data set
  EXPECT_LT(gp_rms, raw_rms);
  double m0, v0, m80, v80;
  gp->Predict(0.0, &m0, &v0);
  gp->Predict(80 * M_PI / 180, &m80, &v80);
  printf("sigma at 0 deg %.2f deg, at 80 deg %.2f deg\n", std::sqrt(v0) * 180 / M_PI, std::sqrt(v80) * 180 / M_PI);
  EXPECT_GT(v80, v0);
}

// (5.23-5.27) as printed: h runs from the anchor, so the linearity index reduces to
// L = 4 sigma_d / |h| = 4 sigma_rho / rho.
TEST(LinearArray, LinearityIndexFromTheAnchorIsFourRelativeInverseDepthSigmas) {
  MultiHypothesisOptions o;
  o.linearity_from_anchor = true;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  MultiHypothesisSource src(o, pose, 0.3, 0.01);
  pose.translation() = Eigen::Vector3d(0.3, 0.1, 0.2);
  src.Update(pose, 0.25, 0.01);
  for (const auto& h : src.hypotheses()) {
    if (!h.alive) continue;
    EXPECT_NEAR(h.linearity, 4 * std::sqrt(h.p(2, 2)) / h.s[2], 1e-9);
  }
}

// (5.21-5.22): the printed S = H P H' leaves out the observation noise, so the same
// innovations score a larger chi-square than with the innovation covariance H P H' + Q.
TEST(LinearArray, ChiSquareAsPrintedLeavesOutTheObservationNoise) {
  MultiHypothesisOptions with_q, without_q;
  without_q.chi2_with_noise = false;
  with_q.prune_z = without_q.prune_z = 0;
  with_q.prune_mean_chi2 = without_q.prune_mean_chi2 = 1e9;
  with_q.relative_prune_chi2 = without_q.relative_prune_chi2 = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  MultiHypothesisSource a(with_q, pose, 0.3, 0.01), b(without_q, pose, 0.3, 0.01);
  pose.translation() = Eigen::Vector3d(0.4, 0.0, 0.0);
  a.Update(pose, 0.35, 0.01);
  b.Update(pose, 0.35, 0.01);
  for (size_t i = 0; i < a.hypotheses().size(); ++i) {
    const auto& ha = a.hypotheses()[i];
    const auto& hb = b.hypotheses()[i];
    EXPECT_GT(hb.chi2_sum, ha.chi2_sum);
  }
}

// §5.5.1's simulated sensor: a GP over the true angle reproduces the calibration's bias and
// spread, and the GP over the raw angle (5.5-5.6) maps the biased estimate back.
TEST(LinearArray, CalibratedDoaReproducesBiasAndSpread) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01(0, 1);
  std::vector<double> raw, truth;
  const double deg = M_PI / 180;
  for (int a = -90; a <= 90; a += 5)
    for (int t = 0; t < 5; ++t) {
      truth.push_back(a * deg);
      raw.push_back(0.8 * a * deg + 3 * deg * n01(rng));  // compressed by 20 %, 3 deg spread
    }
  const CalibratedDoa cal = FitCalibratedDoa(raw, truth);
  double m, v;
  cal.generator->Predict(30 * deg, &m, &v);
  EXPECT_NEAR(m / deg, 24, 2.0);
  EXPECT_NEAR(std::sqrt(v) / deg, 3, 1.0);
  cal.sensor_model->Predict(24 * deg, &m, &v);
  EXPECT_NEAR(m / deg, 30, 2.5);
}

// A forward model g(b) = 0.8 b with 3 deg of noise, inverted by Bayes' rule: the mean undoes
// the compression and the spread grows by 1 / 0.8; a 5 deg grid adds its q^2 / 12.
TEST(BayesInvertedDoaModel, InvertsALinearForwardModel) {
  struct Compressed : DoaSensorModel {
    void Predict(double b, double* mean, double* var) const override {
      *mean = 0.8 * b;
      *var = std::pow(3 * M_PI / 180, 2);
    }
  };
  const double deg = M_PI / 180;
  double m, v;
  BayesInvertedDoaModel(Compressed(), 0).Predict(0.8 * 30 * deg, &m, &v);
  EXPECT_NEAR(m / deg, 30, 0.1);
  EXPECT_NEAR(std::sqrt(v) / deg, 3 / 0.8, 0.05);
  BayesInvertedDoaModel(Compressed(), 5 * deg).Predict(25 * deg, &m, &v);
  EXPECT_NEAR(m / deg, 25 / 0.8, 0.1);
  EXPECT_NEAR(std::sqrt(v) / deg, std::sqrt(9 + 25.0 / 12) / 0.8, 0.05);
  // Beyond what the sensor can report (|g| <= 72 deg): the truth is near endfire.
  BayesInvertedDoaModel(Compressed(), 0).Predict(85 * deg, &m, &v);
  EXPECT_GT(m / deg, 85);
  EXPECT_LE(m / deg, 90);
}

// End to end with nearly exact DOAs (0.5 deg) and the true poses: every source converges,
// and the mapped sources sit on the truth (pins 5.1-5.2, 5.8-5.22 and 5.30-5.31 together).
TEST(LinearArray, NearlyExactDoasMapEverySource) {
  LinearSimConfig c;
  c.trajectory = 2;
  c.seed = 11;
  c.landmark_density_per_m2 = 0.3;  // poses are given
  c.doa_generator = std::make_shared<ConstantDoaModel>(0.5 * M_PI / 180);
  LinearMapperOptions o;
  o.sensor_model = std::make_shared<ConstantDoaModel>(0.5 * M_PI / 180);
  o.oracle_poses = true;
  const LinearRunResult r = RunLinearArrayMapping(SimulateLinear(c), o);
  printf("exact DOAs: rms %.4f floor %.4f converged %d\n", r.rms_m, r.floor_rms_m, r.converged);
  EXPECT_EQ(r.converged, 8);
  EXPECT_LT(r.floor_rms_m, 0.03);
  EXPECT_LT(r.rms_m, 0.03);
}

// Table 5.1 as §5.5.1 simulates it: the DOA error of the real array (its calibration pairs,
// shared/data/audio/ssm) modelled by a GP over the true angle and added to the truth, the
// mapper correcting it with the GP over the raw angle.
class Table51 : public ::testing::Test {
 protected:
  static std::string Path() { return std::string(SARMAP_DATA_DIR) + "/audio/ssm/gp_doa_calibration.csv"; }
  static void SetUpTestSuite() {
    if (!std::ifstream(Path())) return;
    std::vector<double> raw, truth;
    LoadDoaCalibrationCsv(Path(), &raw, &truth);
    cal_ = FitCalibratedDoa(raw, truth, kQuantum);
  }
  static constexpr double kQuantum = 5 * M_PI / 180;  // the calibration's SRP-PHAT grid
  void SetUp() override {
    if (!cal_.generator) GTEST_SKIP() << "shared data missing: " << Path();
  }
  // The mapper as configured by default: raw-angle residuals through the forward model.
  static LinearMapperOptions Mapper() {
    LinearMapperOptions o;
    o.sensor_model = cal_.sensor_model;
    o.forward_model = cal_.generator;
    o.doa_quantum_rad = kQuantum;
    return o;
  }
  static LinearSimConfig Sim(int trajectory, int seed = 3000) {
    LinearSimConfig c;
    c.trajectory = trajectory;
    c.fixed_heading = trajectory == 1;  // facing along the side (see README)
    c.seed = seed;
    c.doa_generator = cal_.generator;
    c.doa_quantum_rad = kQuantum;
    // 2 landmarks per m^2 (~25 per keyframe): these tests pin behaviour on given seeds and stay
    // short; the default 15 (README's Table 5.1) makes each run ~7x longer.
    c.landmark_density_per_m2 = 2;
    return c;
  }
  LinearRunResult Run(int trajectory) {
    const LinearRunResult r = RunLinearArrayMapping(SimulateLinear(Sim(trajectory)), Mapper());
    printf("traj%d rms %.4f floor %.4f conv %.3f (%d), poses %.3f m, %.2f s\n", trajectory, r.rms_m, r.floor_rms_m,
           r.convergence_rate, r.converged, r.pose_rms_m, r.seconds);
    return r;
  }
  static CalibratedDoa cal_;
};
CalibratedDoa Table51::cal_;

TEST_F(Table51, FirstTrajectory) {
  const LinearRunResult r = Run(1);
  // Thesis: 0.1302 m; this seed, with 2 landmarks per m^2, 0.140 m (its own least-squares floor
  // from the true poses: 0.131 m); with the default 15, 0.133 m. With the thesis' correction
  // (5.5-5.6) it was 0.25 m.
  EXPECT_EQ(r.converged, 8);
  EXPECT_LT(r.rms_m, 0.16);
}

TEST_F(Table51, SecondTrajectory) {
  const LinearRunResult r = Run(2);
  EXPECT_EQ(r.converged, 8);
  EXPECT_LE(r.rms_m, 0.2688);  // thesis
}

// With noiseless (but biased) raw angles and the true poses, raw-angle residuals through the
// forward model put every source on the truth. Correcting the raw angles with the GP of the
// truth over the raw angle (5.5-5.6) leaves them off: that regression is fitted on noisy
// inputs, so it undoes only part of the bias.
TEST_F(Table51, ForwardModelIsUnbiasedWhereTheThesisCorrectionIsNot) {
  LinearSimConfig c = Sim(2);
  c.doa_noise_scale = 0;
  c.doa_quantum_rad = 0;
  const LinearSimData d = SimulateLinear(c);
  LinearMapperOptions forward = Mapper(), thesis;
  forward.oracle_poses = thesis.oracle_poses = true;
  thesis.sensor_model = cal_.thesis_model;
  const LinearRunResult f = RunLinearArrayMapping(d, forward), t = RunLinearArrayMapping(d, thesis);
  printf("noiseless raw angles: forward model rms %.4f m, thesis correction rms %.4f m\n", f.rms_m,
         t.rms_m);
  EXPECT_EQ(f.converged, 8);
  EXPECT_LT(f.rms_m, 0.01);
  EXPECT_GT(t.rms_m, 0.05);
}

// A level array hears a source and its mirror image through its own plane alike. In this run
// (seed 3006) one source of a pair converges on the wrong side of the trajectory's plane and
// the optimisation cannot cross back; comparing the two explanations puts it right.
TEST_F(Table51, MirrorCheckPutsASourceOnTheRightSideOfThePlane) {
  const LinearSimData d = SimulateLinear(Sim(1, 3006));
  LinearMapperOptions with = Mapper(), without = Mapper();
  without.mirror_check = false;
  const LinearRunResult a = RunLinearArrayMapping(d, with), b = RunLinearArrayMapping(d, without);
  printf("mirror check: rms %.4f m with, %.4f m without\n", a.rms_m, b.rms_m);
  EXPECT_LT(a.rms_m, 0.2);
  EXPECT_GT(b.rms_m, 0.5);
}

// In this run (seed 3011, ~200 landmarks per keyframe) a window optimisation carries a source
// that has just converged from 9 DOAs off along an asymptote of its cone, 600 km away, where
// its angles barely change, and the later solves never bring it back. A solve that carries a
// source beyond max_source_range_m from every pose that heard it is undone for that source.
TEST_F(Table51, ASourceDoesNotRunOffAlongItsCone) {
  LinearSimConfig c = Sim(1, 3011);
  c.landmark_density_per_m2 = 15;
  const LinearRunResult r = RunLinearArrayMapping(SimulateLinear(c), Mapper());
  double worst = 0;
  for (double e : r.errors_m) worst = std::max(worst, e);
  printf("seed 3011: rms %.4f m, worst source %.3f m\n", r.rms_m, worst);
  EXPECT_EQ(r.converged, 8);
  EXPECT_LT(worst, 0.3);
}

// Fig. 5.8 (reduced: 2 runs of trajectory 2): one hypothesis lands on the wrong part of the
// cone more often than ten. The mirror check, which rescues one such case, is off: this pins
// the hypotheses alone, as the thesis has them.
TEST(LinearArray, Fig58MoreHypothesesMapBetter) {
  double rms[2] = {0, 0}, ok[2] = {0, 0};
  const int nh[2] = {1, 10};
  for (int i = 0; i < 2; ++i)
    for (int r = 0; r < 2; ++r) {
      LinearSimConfig c;
      c.trajectory = 2;
      c.landmark_density_per_m2 = 0.6;  // keeps the test short
      c.seed = 4000 + r;
      LinearMapperOptions o;
      o.num_hypotheses = nh[i];
      o.mirror_check = false;
      const LinearRunResult res = RunLinearArrayMapping(SimulateLinear(c), o);
      rms[i] += res.rms_m / 2;
      ok[i] += res.correct_convergence_rate / 2;
    }
  printf("N_h 1: rms %.3f ok %.2f | N_h 10: rms %.3f ok %.2f\n", rms[0], ok[0], rms[1], ok[1]);
  EXPECT_LT(rms[1], rms[0]);
  EXPECT_GE(ok[1], ok[0]);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
