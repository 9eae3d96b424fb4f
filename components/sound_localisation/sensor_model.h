#pragma once
// Sensor models: the uncertainty (and, for linear arrays, the bias correction) of a DOA.
//
// Constant: covariance diag(sigma^2, sigma^2) for every direction, sigma per array.
// Gaussian process (Su 2017, linear arrays): a 1-D GP maps the raw estimate x (degrees from
// broadside, -90..90) to the true angle y, learnt from pairs (x_i, y_i). With prior mean
// m(x) = x it models the residual r = y - x:
//   k(x, x') = sf^2 exp(-(x - x')^2 / (2 l^2)),   K = k(X, X) + sn^2 I
//   mean(x*) = x* + k*^T K^-1 r,   var(x*) = sf^2 - k*^T K^-1 k* + sn^2
// The hyperparameters (l, sf, sn) maximise the log marginal likelihood
//   -1/2 r^T K^-1 r - 1/2 log|K| - n/2 log 2pi  over a log-spaced grid.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "sound_localisation/array_geometry.h"

namespace sarmap {
namespace sound {

class GaussianProcess1d {
 public:
  struct Hyper {
    double length_scale = 10, signal_sigma = 5, noise_sigma = 3;
  };
  // Fits to (x, y) (same units), choosing hyperparameters by marginal likelihood unless
  // `fixed` is given. Throws std::invalid_argument for fewer than 3 pairs or bad values.
  void Fit(const std::vector<double>& x, const std::vector<double>& y, const Hyper* fixed = nullptr);
  bool fitted() const { return !x_.empty(); }
  // Predicted y and its standard deviation at x.
  void Predict(double x, double* mean, double* sigma) const;
  const Hyper& hyper() const { return hyper_; }
  double LogMarginalLikelihood(const Hyper& h) const;

 private:
  double Kernel(const Hyper& h, double a, double b) const;
  std::vector<double> x_, r_;
  Hyper hyper_;
  Eigen::VectorXd alpha_;
  Eigen::MatrixXd k_inv_;
};

// Reads "estimate,truth" pairs (degrees) from a CSV file; '#' comments and a header line
// are skipped. Throws std::runtime_error naming the file and line on bad rows.
void ReadDoaCalibrationCsv(const std::string& path, std::vector<double>* estimate_deg,
                           std::vector<double>* truth_deg);

class SensorModel {
 public:
  // From the array description; a gp model file is resolved relative to `array_dir`.
  static std::unique_ptr<SensorModel> FromArray(const common::MicArrayOptions& array, const std::string& array_dir);
  static std::unique_ptr<SensorModel> Constant(double sigma_deg);
  static std::unique_ptr<SensorModel> Gp(GaussianProcess1d gp);
  // Corrects `direction` in place (GP) and returns its 2x2 covariance (azimuth, elevation) in
  // rad^2. For kAngle1d the elevation variance is pi^2 (unobservable).
  Eigen::Matrix2d Apply(DoaKind kind, Direction* direction) const;
  std::string name() const { return gp_ ? "gp" : "constant"; }

 private:
  double sigma_rad_ = 0.05;
  std::unique_ptr<GaussianProcess1d> gp_;
};

}  // namespace sound
}  // namespace sarmap
