#pragma once
// Sensor models of a DOA estimate (Su 2017 §5.2): they turn the raw angle reported by a DOA
// method into a mean and a variance for the estimator. A linear array's error depends on
// the angle (worst at endfire, +-90 deg) and is biased there, so the GP model learns the
// mapping raw -> true from calibration pairs:
//   mean     (5.5):  k*' (K + sn^2 I)^-1 y
//   variance (5.6):  k** - k*' (K + sn^2 I)^-1 k*   (+ the local noise level, below)
//   kernel   (5.7):  k(a, b) = sf^2 exp(-(a - b)^2 / (2 l^2))
// with (l, sf, sn) chosen by maximum marginal likelihood over a grid. Because sn is one
// constant, the angle-dependent noise is added as a kernel-weighted mean of the squared
// training residuals around the query (a heteroscedastic term the thesis' libgp lacks).
// Predictions are tabulated on a fine grid at fit time, so Predict() is O(1). (The live DOA
// stream's GP, sound_localisation/sensor_model.h, corrects and weights each DOA as it is
// estimated; this one, with its angle-dependent noise, serves the sound map's estimators.)

#include <memory>
#include <string>
#include <vector>

namespace sarmap {
namespace sound_map {

class DoaSensorModel {
 public:
  virtual ~DoaSensorModel() = default;
  // raw_rad: the DOA method's angle; returns the corrected angle and its variance (rad^2).
  virtual void Predict(double raw_rad, double* mean_rad, double* variance_rad2) const = 0;
};

class ConstantDoaModel : public DoaSensorModel {
 public:
  explicit ConstantDoaModel(double sigma_rad) : sigma_rad_(sigma_rad) {}
  void Predict(double raw_rad, double* mean_rad, double* variance_rad2) const override {
    *mean_rad = raw_rad;
    *variance_rad2 = sigma_rad_ * sigma_rad_;
  }

 private:
  double sigma_rad_;
};

class GpDoaModel : public DoaSensorModel {
 public:
  struct Hyper {
    double length_rad = 0.3, sigma_f_rad = 1.0, sigma_n_rad = 0.2;
  };
  // Fits on pairs (raw estimate, truth), radians; throws std::invalid_argument on < 3 pairs.
  static std::unique_ptr<GpDoaModel> Fit(const std::vector<double>& raw_rad,
                                         const std::vector<double>& true_rad);
  // Reads a CSV with a header line and columns raw_deg,true_deg (shared/data/audio/ssm).
  static std::unique_ptr<GpDoaModel> FitCsvDegrees(const std::string& path);
  void Predict(double raw_rad, double* mean_rad, double* variance_rad2) const override;
  const Hyper& hyper() const { return hyper_; }
  double log_marginal_likelihood() const { return lml_; }

 private:
  Hyper hyper_;
  double lml_ = 0;
  double grid_lo_ = 0, grid_step_ = 0;
  std::vector<double> grid_mean_, grid_var_;
};

// The raw -> true model obtained from a forward model (true -> raw: mean g(b), variance
// s^2(b), e.g. a GpDoaModel fitted on (true, raw) pairs) by Bayes' rule with a flat prior
// on the true angle b in [-90, 90] deg. For a DOA method whose angles lie on a grid of
// step q (the SRP-PHAT grid), the likelihood of the reported cell is
//   P(r | b) = Phi((r + q/2 - g(b)) / s(b)) - Phi((r - q/2 - g(b)) / s(b))
// (q = 0: the Gaussian density N(r; g(b), s^2(b))), and
//   mean = E[b | r],  variance = Var[b | r].
// Why not the GP of the truth over the raw angle (5.5-5.6)? That regression is fitted on
// noisy inputs, so it flattens the bias correction (regression dilution): with exact
// estimates it leaves the sources of §5.5.1 0.09-0.18 m off. Inverting the forward model keeps
// the correction exact where g is steep, and its variance grows where g flattens (endfire).
class BayesInvertedDoaModel : public DoaSensorModel {
 public:
  BayesInvertedDoaModel(const DoaSensorModel& forward, double quantum_rad);
  void Predict(double raw_rad, double* mean_rad, double* variance_rad2) const override;

 private:
  double grid_lo_ = 0, grid_step_ = 0;
  std::vector<double> grid_mean_, grid_var_;
};

}  // namespace sound_map
}  // namespace sarmap
