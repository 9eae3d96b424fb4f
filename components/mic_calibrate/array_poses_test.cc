// Known array motion, static source (CalibrateWithArrayPoses): a Kinect-like line of four
// separate sound cards on a robot that turns in place near one source.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "common/robot_config.h"
#include "log-tools/lcm_log_writer.h"
#include "mic_calibrate/calibration.h"
#include "mic_calibrate/calibration_io.h"
#include "sarmap/odometry_t.hpp"

namespace sarmap {
namespace mic_calibrate {
namespace {

constexpr double kC = 343.0;

struct Scenario {
  std::vector<Eigen::Vector3d> mics = {{-0.113, 0, 0}, {0.036, 0, 0}, {0.076, 0, 0}, {0.113, 0, 0}};
  std::vector<double> tau = {0, 2.13e-3, -4.57e-3, 1.18e-3};
  std::vector<double> delta = {0, 20e-6, -35e-6, 12e-6};
  Eigen::Vector3d source{0.0, 0.0, 0.6};
  Eigen::Vector2d base{1.5, 0.3};     // the robot turns in place here
  double base_from_array_x = 0.10;    // the array 0.1 m ahead of the turning centre, 0.6 m up
  double turn_rad = 2 * M_PI;         // total turn over the recording
  int emissions = 200;
  double step_s = 0.5;
  double noise_s = 20e-6;
  double odometry_rot_sigma = 0.0;    // heading random walk per sqrt(rad) in the given poses
};

struct Synthetic {
  TdoaData data;
  std::vector<Eigen::Isometry3d> true_poses, given_poses;
};

Eigen::Isometry3d ArrayPose(const Scenario& sc, double yaw) {
  Eigen::Isometry3d w = Eigen::Isometry3d::Identity();
  w.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  w.translation() = Eigen::Vector3d(sc.base.x(), sc.base.y(), 0.6) +
                    w.linear() * Eigen::Vector3d(sc.base_from_array_x, 0, 0);
  return w;
}

// z_n(k) = (|m_n(k) - s| - |m_1(k) - s|) / c + tau_n + t_k delta_n + noise.
Synthetic Make(const Scenario& sc, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0, 1);
  Synthetic out;
  const int N = static_cast<int>(sc.mics.size()), K = sc.emissions;
  out.data.num_mics = N;
  out.data.tdoa_s.resize(K, N - 1);
  double heading_error = 0;
  const double dyaw = sc.turn_rad / std::max(1, K - 1);
  for (int k = 0; k < K; ++k) {
    const double t = 0.2 + k * sc.step_s, yaw = 0.4 + k * dyaw;
    if (k > 0) heading_error += sc.odometry_rot_sigma * std::sqrt(std::abs(dyaw)) * normal(rng);
    out.true_poses.push_back(ArrayPose(sc, yaw));
    out.given_poses.push_back(ArrayPose(sc, yaw + heading_error));
    out.data.times_s.push_back(t);
    const Eigen::Vector3d m1 = out.true_poses.back() * sc.mics[0];
    for (int n = 1; n < N; ++n) {
      const Eigen::Vector3d mn = out.true_poses.back() * sc.mics[n];
      out.data.tdoa_s(k, n - 1) = ((mn - sc.source).norm() - (m1 - sc.source).norm()) / kC +
                                  sc.tau[n] + t * sc.delta[n] + sc.noise_s * normal(rng);
    }
  }
  return out;
}

SolverOptions Options(const Scenario& sc) {
  SolverOptions o;
  o.geometry = "linear";
  o.speed_of_sound_mps = kC;
  o.tdoa_sigma_s = sc.noise_s;
  return o;
}

// The worst clock error over the recording (what the DOA sees): |dtau + t dtau/dt| at its ends.
double WorstClockError(const CalibrationResult& r, const Scenario& sc, double t_end) {
  double worst = 0;
  for (size_t n = 1; n < sc.mics.size(); ++n) {
    for (double t : {0.0, t_end}) {
      worst = std::max(worst, std::abs(r.start_offsets_s[n] - sc.tau[n] +
                                       t * (r.clock_drift[n] - sc.delta[n])));
    }
  }
  return worst;
}

// Exact poses: offsets and drifts to a few microseconds (the collinear confound is broken),
// within the reported covariance, and the source where it is.
TEST(ArrayPoses, TurnInPlaceRecoversOffsetsAndDrifts) {
  const Scenario sc;
  const Synthetic syn = Make(sc, 11);
  const CalibrationResult r = CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, Options(sc));
  const double t_end = syn.data.times_s.back();
  printf("[ figures  ] turn in place: source (%.4f, %.4f) m, worst clock error %.2f us, "
         "bearing span %.1f deg, residual rms %.2f us\n", r.source_positions_m[0].x(),
         r.source_positions_m[0].y(), WorstClockError(r, sc, t_end) * 1e6, r.bearing_span_deg,
         r.residual_rms_s * 1e6);
  EXPECT_LT((r.source_positions_m[0] - sc.source).norm(), 0.05);
  EXPECT_LT(WorstClockError(r, sc, t_end), 5e-6);
  ASSERT_TRUE(r.has_covariance);
  for (int n = 1; n < 4; ++n) {
    const double std_tau = std::sqrt(r.clock_cov[n](0, 0)), std_delta = std::sqrt(r.clock_cov[n](1, 1));
    EXPECT_GT(std_tau, 0);
    EXPECT_LT(std::abs(r.start_offsets_s[n] - sc.tau[n]), 4 * std_tau) << "mic " << n + 1;
    EXPECT_LT(std::abs(r.clock_drift[n] - sc.delta[n]), 4 * std_delta) << "mic " << n + 1;
  }
  EXPECT_GT(r.bearing_span_deg, 170);  // a full turn: every bearing (folded to 0..180)
  // The reported clock uncertainty: a few us over the recording, growing beyond it.
  printf("[ figures  ] clock std %.2f us at the end, %.2f us at twice the length\n",
         ClockStdAt(r, t_end) * 1e6, ClockStdAt(r, 2 * t_end) * 1e6);
  EXPECT_GT(ClockStdAt(r, t_end), 0.3e-6);
  EXPECT_LT(ClockStdAt(r, t_end), 5e-6);
  EXPECT_GT(ClockStdAt(r, 2 * t_end), 1.5 * ClockStdAt(r, t_end));
  EXPECT_NEAR(r.residual_rms_s, sc.noise_s, 0.2 * sc.noise_s);
}

// Poses from drifting odometry: as exact poses they bias the clocks; as a pose graph with
// the odometry's noise model they do not (much).
TEST(ArrayPoses, OdometryDriftAsPoseGraph) {
  Scenario sc;
  sc.odometry_rot_sigma = 0.03;
  sc.turn_rad = 4 * M_PI;
  sc.emissions = 240;
  const Synthetic syn = Make(sc, 5);
  const double t_end = syn.data.times_s.back();
  SolverOptions o = Options(sc);
  const CalibrationResult exact = CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, o);
  o.pose_rot_sigma_per_sqrt_rad = sc.odometry_rot_sigma;
  o.pose_trans_sigma_per_sqrt_m = 0.02;
  const CalibrationResult graph = CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, o);
  const double truth_rad = std::atan2(syn.given_poses.back().linear()(1, 0), syn.given_poses.back().linear()(0, 0));
  printf("[ figures  ] odometry drift %.2f deg at the end: worst clock error %.2f us as exact "
         "poses, %.2f us as a pose graph\n",
         std::remainder(truth_rad - (0.4 + sc.turn_rad), 2 * M_PI) * 180 / M_PI,
         WorstClockError(exact, sc, t_end) * 1e6, WorstClockError(graph, sc, t_end) * 1e6);
  EXPECT_LT(WorstClockError(graph, sc, t_end), 6e-6);
  EXPECT_LT(WorstClockError(graph, sc, t_end), WorstClockError(exact, sc, t_end));
}

TEST(ArrayPoses, ArrayThatNeverMovesIsRefused) {
  Scenario sc;
  sc.turn_rad = 0;
  const Synthetic syn = Make(sc, 3);
  try {
    CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, Options(sc));
    FAIL() << "expected UnobservableError";
  } catch (const UnobservableError& e) {
    EXPECT_NE(std::string(e.what()).find("never moved"), std::string::npos) << e.what();
  }
}

// A 20 deg turn: the bearing span is too small to tell clocks from direction.
TEST(ArrayPoses, SmallTurnIsRefusedWithTheConfound) {
  Scenario sc;
  sc.turn_rad = 20 * M_PI / 180;
  const Synthetic syn = Make(sc, 3);
  try {
    CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, Options(sc));
    FAIL() << "expected UnobservableError";
  } catch (const UnobservableError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bearing"), std::string::npos) << what;
    EXPECT_NE(what.find("one line"), std::string::npos) << what;
  }
}

TEST(ArrayPoses, NanTdoasAndBadInput) {
  const Scenario sc;
  Synthetic syn = Make(sc, 13);
  for (int k = 0; k < syn.data.num_emissions(); k += 7) syn.data.tdoa_s(k, 1) = std::nan("");
  const CalibrationResult r = CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, Options(sc));
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("missing"), std::string::npos);
  EXPECT_LT(WorstClockError(r, sc, syn.data.times_s.back()), 10e-6);
  // Every TDOA of one card missing: refused, naming the card.
  for (int k = 0; k < syn.data.num_emissions(); ++k) syn.data.tdoa_s(k, 2) = std::nan("");
  try {
    CalibrateWithArrayPoses(syn.data, syn.given_poses, sc.mics, Options(sc));
    FAIL() << "expected UnobservableError";
  } catch (const UnobservableError& e) {
    EXPECT_NE(std::string(e.what()).find("mic 4"), std::string::npos) << e.what();
  }
  // One pose short: a clear error.
  std::vector<Eigen::Isometry3d> fewer = syn.given_poses;
  fewer.pop_back();
  EXPECT_THROW(CalibrateWithArrayPoses(syn.data, fewer, sc.mics, Options(sc)), std::invalid_argument);
}

// The absolute emission times (to look up the poses) survive the TDOA CSV.
TEST(ArrayPoses, UtimesRoundTripThroughTdoaCsv) {
  const Scenario sc;
  Synthetic syn = Make(sc, 17);
  for (int k = 0; k < syn.data.num_emissions(); ++k) {
    syn.data.utimes.push_back(1700000000000000LL + static_cast<int64_t>(syn.data.times_s[k] * 1e6) + 7);
  }
  const std::string path = std::string(SARMAP_BIN_DIR) + "/array_poses_test_tdoa.csv";
  WriteTdoaCsv(path, syn.data);
  const TdoaCsv back = ReadTdoaCsv(path, 0.5);
  ASSERT_EQ(back.data.utimes.size(), syn.data.utimes.size());
  EXPECT_EQ(back.data.utimes.front(), syn.data.utimes.front());
  EXPECT_EQ(back.data.utimes.back(), syn.data.utimes.back());
}

// The CLI: TDOA CSV with utimes + an LCM log of ODOM (odometry_t of the base, 20 Hz); the
// array frame from config/robot.yaml's base_from_mic_array (0.1 m ahead, 0.6 m up, as above).
TEST(ArrayPoses, CliWithOdomFromAnLcmLog) {
  const Scenario sc;
  Synthetic syn = Make(sc, 19);
  const int64_t t0 = 1700000000000000LL;
  for (double t : syn.data.times_s) syn.data.utimes.push_back(t0 + std::llround(t * 1e6));
  const std::string dir = ::testing::TempDir();
  const std::string csv = dir + "/array_poses_cli.csv", log = dir + "/array_poses_cli.lcmlog",
                    yaml = dir + "/array_poses_cli.yaml";
  WriteTdoaCsv(csv, syn.data);
  {
    logtools::LcmLogWriter out(log);
    const double dyaw = sc.turn_rad / (sc.emissions - 1);
    for (int i = 0; i * 0.05 <= syn.data.times_s.back() + 1; ++i) {
      const double t = i * 0.05, yaw = 0.4 + (t - 0.2) / sc.step_s * dyaw;
      sarmap::odometry_t odom{};
      odom.header.utime = t0 + std::llround(t * 1e6);
      odom.header.frame = "odom";
      odom.child_frame = "base";
      odom.position_m[0] = sc.base.x();
      odom.position_m[1] = sc.base.y();
      odom.orientation[0] = std::cos(yaw / 2);
      odom.orientation[3] = std::sin(yaw / 2);
      out.Write("ODOM", odom, odom.header.utime);
    }
  }
  const std::string src = SARMAP_SOURCE_DIR;
  const std::string cmd = std::string(SARMAP_BIN_DIR) + "/sarmap-mic-calibrate " + csv +
                          " --poses " + log + " --config " + src + "/config/mic_calibrate.yaml" +
                          " --set array_poses.channel=ODOM --set array_poses.robot_config=" + src +
                          "/config/robot.yaml --nominal " + src + "/config/arrays/kinect.yaml" +
                          " --set solver.geometry=linear --set solver.speed_of_sound_mps=343" +
                          " --set solver.tdoa_sigma_s=2e-5 --output " + yaml + " --quiet";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const common::MicArrayOptions a = common::LoadMicArray(yaml);
  ASSERT_EQ(a.num_mics(), 4);
  EXPECT_EQ(a.geometry, "linear");
  for (int n = 1; n < 4; ++n) {
    EXPECT_NEAR(a.mic_position(n).x(), sc.mics[n].x(), 1e-9);  // as given (array frame)
    EXPECT_NEAR(a.start_offsets_s[n], sc.tau[n], 8e-6) << n;
    EXPECT_NEAR(a.clock_drift[n], sc.delta[n], 0.1e-6) << n;
  }
}

}  // namespace
}  // namespace mic_calibrate
}  // namespace sarmap
