#include "sound_localisation/sensor_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "common/robot_config.h"

namespace sarmap {
namespace sound {
namespace {

double Rms(const std::vector<double>& e) {
  double s = 0;
  for (double v : e) s += v * v;
  return std::sqrt(s / e.size());
}

TEST(GaussianProcess, LearnsASmoothBias) {
  // Estimates compressed toward broadside: est = 0.8 truth; the GP must learn the inverse.
  std::vector<double> x, y;
  for (int t = -90; t <= 90; t += 5) {
    x.push_back(0.8 * t);
    y.push_back(t);
  }
  GaussianProcess1d gp;
  gp.Fit(x, y);
  double mean, sigma;
  gp.Predict(0.8 * 42.0, &mean, &sigma);
  EXPECT_NEAR(mean, 42.0, 1.0);
  EXPECT_LT(sigma, 5.0);
  EXPECT_THROW(gp.Fit({1.0}, {1.0}), std::invalid_argument);
}

TEST(SensorModel, ConstantAndLinearGpCovariance) {
  Direction d{DegToRad(30), DegToRad(10)};
  const auto c = SensorModel::Constant(3.0)->Apply(DoaKind::kAzimuthElevation, &d);
  EXPECT_NEAR(std::sqrt(c(0, 0)), DegToRad(3.0), 1e-12);
  EXPECT_NEAR(std::sqrt(c(1, 1)), DegToRad(3.0), 1e-12);
  const auto c1 = SensorModel::Constant(3.0)->Apply(DoaKind::kAngle1d, &d);
  EXPECT_NEAR(c1(1, 1), M_PI * M_PI, 1e-12);  // elevation unobservable
}

// Real training set (Su 2017): SRP-PHAT estimates of a real linear array vs true azimuth.
// Fit on 7 of every 10 trials per angle, test on the other 3.
TEST(SensorModelRealData, GpLowersRmsErrorOnHeldBackRows) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/ssm/gp_doa_calibration.csv";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  std::vector<double> est, truth;
  ReadDoaCalibrationCsv(path, &est, &truth);
  ASSERT_EQ(est.size(), 370u);
  std::vector<double> xtr, ytr, raw_err, gp_err;
  std::vector<std::pair<double, double>> test;
  for (size_t i = 0; i < est.size(); ++i) {
    if (i % 10 < 7) {
      xtr.push_back(est[i]);
      ytr.push_back(truth[i]);
    } else {
      test.emplace_back(est[i], truth[i]);
    }
  }
  GaussianProcess1d gp;
  gp.Fit(xtr, ytr);
  int inside = 0;
  for (const auto& [x, y] : test) {
    double mean, sigma;
    gp.Predict(x, &mean, &sigma);
    raw_err.push_back(x - y);
    gp_err.push_back(mean - y);
    inside += std::abs(mean - y) <= 2 * sigma;
  }
  const double raw = Rms(raw_err), corrected = Rms(gp_err);
  std::printf("GP sensor model on %zu held-back rows (trained on %zu): RMS raw %.2f deg -> GP %.2f deg; "
              "%.0f%% within 2 sigma; hyper l=%.1f sf=%.1f sn=%.1f deg\n",
              test.size(), xtr.size(), raw, corrected, 100.0 * inside / test.size(), gp.hyper().length_scale,
              gp.hyper().signal_sigma, gp.hyper().noise_sigma);
  EXPECT_LT(corrected, raw);
  EXPECT_GT(inside, 0.8 * test.size());
}

TEST(SensorModelRealData, GpArrayConfigCorrectsEndFire) {
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/ssm/gp_doa_calibration.csv";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  auto array = common::LoadMicArray(std::string(SARMAP_SOURCE_DIR) + "/config/arrays/ps3eye_gp.yaml");
  array.gp_model_file = path;  // the worktree may not sit beside shared/
  const auto model = SensorModel::FromArray(array, "");
  EXPECT_EQ(model->name(), "gp");
  // The raw estimates saturate short of end-fire (a true 90 deg reads about 60-70 deg from
  // broadside): a raw 65 deg from broadside (25 deg to the axis) is pushed toward the axis.
  Direction d{DegToRad(25), 0};
  const auto cov = model->Apply(DoaKind::kAngle1d, &d);
  std::printf("GP: raw 25 deg to the axis -> %.1f deg, sigma %.1f deg\n", RadToDeg(d.azimuth_rad), RadToDeg(std::sqrt(cov(0, 0))));
  EXPECT_LT(RadToDeg(d.azimuth_rad), 25.0);
  Direction b{DegToRad(90), 0};  // broadside stays put
  model->Apply(DoaKind::kAngle1d, &b);
  EXPECT_NEAR(RadToDeg(b.azimuth_rad), 90.0, 5.0);
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
