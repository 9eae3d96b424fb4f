#include "handheld_sound_map/doa_sensor_model.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace sound_map {

namespace {

Eigen::MatrixXd Kernel(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double l, double sf) {
  Eigen::MatrixXd k(a.size(), b.size());
  for (int i = 0; i < a.size(); ++i)
    for (int j = 0; j < b.size(); ++j) k(i, j) = sf * sf * std::exp(-0.5 * std::pow((a[i] - b[j]) / l, 2));
  return k;
}

}  // namespace

std::unique_ptr<GpDoaModel> GpDoaModel::Fit(const std::vector<double>& raw, const std::vector<double>& truth) {
  if (raw.size() != truth.size() || raw.size() < 3)
    throw std::invalid_argument("GpDoaModel::Fit: need at least 3 (raw, true) pairs of equal count");
  const int n = static_cast<int>(raw.size());
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(raw.data(), n);
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(truth.data(), n);
  auto model = std::make_unique<GpDoaModel>();
  // Maximum marginal likelihood over a log grid:
  //   log p(y) = -1/2 y' Ky^-1 y - sum log diag(L) - n/2 log 2pi,  Ky = K + sn^2 I = L L'.
  double best = -1e300;
  for (double l : {0.1, 0.2, 0.35, 0.6, 1.0, 1.7}) {
    for (double sf : {0.5, 1.0, 2.0}) {
      for (double sn : {0.05, 0.1, 0.15, 0.2, 0.3, 0.45}) {
        Eigen::MatrixXd ky = Kernel(x, x, l, sf);
        ky.diagonal().array() += sn * sn;
        const Eigen::LLT<Eigen::MatrixXd> llt(ky);
        if (llt.info() != Eigen::Success) continue;
        const Eigen::VectorXd alpha = llt.solve(y);
        const double lml = -0.5 * y.dot(alpha) - llt.matrixL().toDenseMatrix().diagonal().array().log().sum() -
                           0.5 * n * std::log(2 * M_PI);
        if (lml > best) {
          best = lml;
          model->hyper_ = Hyper{l, sf, sn};
        }
      }
    }
  }
  model->lml_ = best;
  const Hyper& h = model->hyper_;
  Eigen::MatrixXd ky = Kernel(x, x, h.length_rad, h.sigma_f_rad);
  ky.diagonal().array() += h.sigma_n_rad * h.sigma_n_rad;
  const Eigen::LLT<Eigen::MatrixXd> llt(ky);
  const Eigen::VectorXd alpha = llt.solve(y);
  // Training residuals for the angle-dependent noise term.
  const Eigen::VectorXd fit = Kernel(x, x, h.length_rad, h.sigma_f_rad) * alpha;
  const Eigen::VectorXd res2 = (y - fit).array().square();
  const double lo = std::min(x.minCoeff(), -M_PI / 2), hi = std::max(x.maxCoeff(), M_PI / 2);
  const int grid = 721;
  model->grid_lo_ = lo;
  model->grid_step_ = (hi - lo) / (grid - 1);
  Eigen::VectorXd q(grid);
  for (int i = 0; i < grid; ++i) q[i] = lo + i * model->grid_step_;
  const Eigen::MatrixXd ks = Kernel(q, x, h.length_rad, h.sigma_f_rad);  // grid x n
  const Eigen::VectorXd mean = ks * alpha;
  const Eigen::MatrixXd v = llt.matrixL().solve(ks.transpose());  // n x grid
  model->grid_mean_.resize(grid);
  model->grid_var_.resize(grid);
  // Noise bandwidth: half the kernel length, at least 5 deg (the calibration grid step).
  const double bw = std::max(0.5 * h.length_rad, 5.0 * M_PI / 180);
  for (int i = 0; i < grid; ++i) {
    const double epistemic = std::max(0.0, h.sigma_f_rad * h.sigma_f_rad - v.col(i).squaredNorm());
    double wsum = 0, r2 = 0;
    for (int j = 0; j < n; ++j) {
      const double w = std::exp(-0.5 * std::pow((q[i] - x[j]) / bw, 2));
      wsum += w;
      r2 += w * res2[j];
    }
    const double noise = wsum > 1e-9 ? r2 / wsum : h.sigma_n_rad * h.sigma_n_rad;
    model->grid_mean_[i] = mean[i];
    model->grid_var_[i] = epistemic + std::max(noise, 1e-6);
  }
  return model;
}

std::unique_ptr<GpDoaModel> GpDoaModel::FitCsvDegrees(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read GP calibration file " + path);
  std::vector<double> raw, truth;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    double a, b;
    if (!(s >> a >> b)) continue;  // header
    raw.push_back(a * M_PI / 180);
    truth.push_back(b * M_PI / 180);
  }
  return Fit(raw, truth);
}

void GpDoaModel::Predict(double raw_rad, double* mean_rad, double* variance_rad2) const {
  const double f = (raw_rad - grid_lo_) / grid_step_;
  const int last = static_cast<int>(grid_mean_.size()) - 1;
  const double fc = std::clamp(f, 0.0, static_cast<double>(last));
  const int i = std::min(static_cast<int>(fc), last - 1);
  const double t = fc - i;
  *mean_rad = (1 - t) * grid_mean_[i] + t * grid_mean_[i + 1];
  *variance_rad2 = (1 - t) * grid_var_[i] + t * grid_var_[i + 1];
}

BayesInvertedDoaModel::BayesInvertedDoaModel(const DoaSensorModel& forward, double quantum_rad) {
  const int n = 721;  // 0.25 deg cells over [-90, 90] deg for both the raw and the true angle
  grid_lo_ = -M_PI / 2;
  grid_step_ = M_PI / (n - 1);
  std::vector<double> g(n), s(n);
  for (int j = 0; j < n; ++j) {
    double var;
    forward.Predict(grid_lo_ + j * grid_step_, &g[j], &var);
    s[j] = std::sqrt(std::max(var, 1e-10));
  }
  auto phi = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  grid_mean_.resize(n);
  grid_var_.resize(n);
  for (int i = 0; i < n; ++i) {
    const double r = grid_lo_ + i * grid_step_;
    double w_sum = 0, b_sum = 0, b2_sum = 0;
    for (int j = 0; j < n; ++j) {
      const double b = grid_lo_ + j * grid_step_;
      const double w = quantum_rad > 0 ? phi((r + 0.5 * quantum_rad - g[j]) / s[j]) -
                                             phi((r - 0.5 * quantum_rad - g[j]) / s[j])
                                       : std::exp(-0.5 * std::pow((r - g[j]) / s[j], 2)) / s[j];
      w_sum += w;
      b_sum += w * b;
      b2_sum += w * b * b;
    }
    if (w_sum < 1e-300) {  // r beyond anything the sensor reports: the nearest mean's angle
      int best = 0;
      for (int j = 1; j < n; ++j)
        if (std::abs(g[j] - r) < std::abs(g[best] - r)) best = j;
      grid_mean_[i] = grid_lo_ + best * grid_step_;
      grid_var_[i] = std::pow(s[best], 2);
      continue;
    }
    grid_mean_[i] = b_sum / w_sum;
    // The flat prior's cells add their own width (q^2 / 12 of a 0.25 deg cell: negligible).
    grid_var_[i] = std::max(b2_sum / w_sum - grid_mean_[i] * grid_mean_[i], 1e-8);
  }
}

void BayesInvertedDoaModel::Predict(double raw_rad, double* mean_rad, double* variance_rad2) const {
  const double f = std::clamp((raw_rad - grid_lo_) / grid_step_, 0.0, grid_mean_.size() - 1.0);
  const int i = std::min(static_cast<int>(f), static_cast<int>(grid_mean_.size()) - 2);
  const double t = f - i;
  *mean_rad = (1 - t) * grid_mean_[i] + t * grid_mean_[i + 1];
  *variance_rad2 = (1 - t) * grid_var_[i] + t * grid_var_[i + 1];
}

}  // namespace sound_map
}  // namespace sarmap
