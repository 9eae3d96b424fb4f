#include "sound_localisation/sensor_model.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace sound {

double GaussianProcess1d::Kernel(const Hyper& h, double a, double b) const {
  const double d = (a - b) / h.length_scale;
  return h.signal_sigma * h.signal_sigma * std::exp(-0.5 * d * d);
}

double GaussianProcess1d::LogMarginalLikelihood(const Hyper& h) const {
  const int n = static_cast<int>(x_.size());
  Eigen::MatrixXd K(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) K(i, j) = Kernel(h, x_[i], x_[j]) + (i == j ? h.noise_sigma * h.noise_sigma : 0);
  Eigen::LLT<Eigen::MatrixXd> llt(K);
  if (llt.info() != Eigen::Success) return -INFINITY;
  const Eigen::VectorXd r = Eigen::Map<const Eigen::VectorXd>(r_.data(), n);
  const Eigen::VectorXd a = llt.solve(r);
  const double logdet = 2 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  return -0.5 * r.dot(a) - 0.5 * logdet - 0.5 * n * std::log(2 * M_PI);
}

void GaussianProcess1d::Fit(const std::vector<double>& x, const std::vector<double>& y, const Hyper* fixed) {
  if (x.size() != y.size() || x.size() < 3) throw std::invalid_argument("GP needs >= 3 (x, y) pairs");
  x_ = x;
  r_.resize(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) throw std::invalid_argument("GP data must be finite");
    r_[i] = y[i] - x[i];
  }
  if (fixed) {
    hyper_ = *fixed;
  } else {
    double best = -INFINITY;
    for (double l : {2.0, 4.0, 8.0, 16.0, 32.0, 64.0})
      for (double sf : {1.0, 3.0, 10.0, 30.0})
        for (double sn : {0.5, 1.0, 2.0, 4.0, 6.0, 8.0, 12.0, 16.0}) {
          const Hyper h{l, sf, sn};
          const double ll = LogMarginalLikelihood(h);
          if (ll > best) {
            best = ll;
            hyper_ = h;
          }
        }
  }
  const int n = static_cast<int>(x_.size());
  Eigen::MatrixXd K(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      K(i, j) = Kernel(hyper_, x_[i], x_[j]) + (i == j ? hyper_.noise_sigma * hyper_.noise_sigma : 0);
  Eigen::LLT<Eigen::MatrixXd> llt(K);
  alpha_ = llt.solve(Eigen::Map<const Eigen::VectorXd>(r_.data(), n));
  k_inv_ = llt.solve(Eigen::MatrixXd::Identity(n, n));
}

void GaussianProcess1d::Predict(double x, double* mean, double* sigma) const {
  const int n = static_cast<int>(x_.size());
  Eigen::VectorXd ks(n);
  for (int i = 0; i < n; ++i) ks(i) = Kernel(hyper_, x, x_[i]);
  *mean = x + ks.dot(alpha_);
  const double var = hyper_.signal_sigma * hyper_.signal_sigma - ks.dot(k_inv_ * ks) +
                     hyper_.noise_sigma * hyper_.noise_sigma;
  *sigma = std::sqrt(std::max(var, 1e-12));
}

void ReadDoaCalibrationCsv(const std::string& path, std::vector<double>* est, std::vector<double>* truth) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open DOA calibration file");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t') c = ' ';
    std::istringstream s(line);
    double a, b;
    if (!(s >> a >> b)) {
      if (est->empty() && std::isalpha(static_cast<unsigned char>(line[0]))) continue;  // header
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected 'estimate,truth' numbers");
    }
    est->push_back(a);
    truth->push_back(b);
  }
}

std::unique_ptr<SensorModel> SensorModel::Constant(double sigma_deg) {
  auto m = std::make_unique<SensorModel>();
  m->sigma_rad_ = DegToRad(sigma_deg);
  return m;
}

std::unique_ptr<SensorModel> SensorModel::Gp(GaussianProcess1d gp) {
  auto m = std::make_unique<SensorModel>();
  m->gp_ = std::make_unique<GaussianProcess1d>(std::move(gp));
  return m;
}

std::unique_ptr<SensorModel> SensorModel::FromArray(const common::MicArrayOptions& array, const std::string& dir) {
  if (array.sensor_model != "gp") return Constant(array.doa_sigma_deg);
  if (array.geometry != "linear")
    throw std::invalid_argument("array '" + array.name + "': the gp sensor model is for linear arrays only");
  std::string path = array.gp_model_file;
  if (!path.empty() && path[0] != '/' && !dir.empty()) path = dir + "/" + path;
  std::vector<double> x, y;
  ReadDoaCalibrationCsv(path, &x, &y);
  GaussianProcess1d gp;
  gp.Fit(x, y);
  return Gp(std::move(gp));
}

Eigen::Matrix2d SensorModel::Apply(DoaKind kind, Direction* d) const {
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  double sigma = sigma_rad_;
  if (gp_ && kind == DoaKind::kAngle1d) {
    // The GP works in degrees from broadside: 90 - angle to the axis.
    const double x = 90.0 - RadToDeg(d->azimuth_rad);
    double mean, s;
    gp_->Predict(x, &mean, &s);
    mean = std::clamp(mean, -90.0, 90.0);
    d->azimuth_rad = DegToRad(90.0 - mean);
    sigma = DegToRad(s);
  }
  cov(0, 0) = sigma * sigma;
  cov(1, 1) = kind == DoaKind::kAzimuthElevation ? sigma * sigma : M_PI * M_PI;
  return cov;
}

}  // namespace sound
}  // namespace sarmap
