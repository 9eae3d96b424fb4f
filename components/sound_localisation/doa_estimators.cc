#include "sound_localisation/doa_estimators.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace sarmap {
namespace sound {

void BlockStatistics::Reset(int num_mics) {
  const int n = num_bins();
  raw.assign(n, Eigen::MatrixXcd::Zero(num_mics, num_mics));
  phat.assign(n, Eigen::MatrixXcd::Zero(num_mics, num_mics));
  num_frames = 0;
}

void BlockStatistics::Add(const BlockStatistics& other) {
  for (size_t k = 0; k < raw.size() && k < other.raw.size(); ++k) {
    raw[k] += other.raw[k];
    phat[k] += other.phat[k];
  }
  num_frames += other.num_frames;
}

BlockStatistics SubtractNoiseCrossSpectra(const BlockStatistics& stats, double beta) {
  BlockStatistics out = stats;
  if (beta <= 0 || stats.noise.size() != stats.raw.size()) return out;
  for (size_t k = 0; k < out.raw.size(); ++k) {
    const Eigen::MatrixXcd& r = stats.raw[k];
    const Eigen::MatrixXcd& noise = stats.noise[k];
    Eigen::MatrixXcd& phat = out.phat[k];
    const double n_k = phat.rows() > 0 ? phat(0, 0).real() : 0.0;  // |Y_m| = 1 per frame
    if (n_k <= 0) continue;
    for (int i = 0; i < r.rows(); ++i)
      for (int j = i + 1; j < r.cols(); ++j) {
        const double r_abs = std::abs(r(i, j));
        if (r_abs <= 0) continue;
        ComplexD g = (r(i, j) - beta * n_k * noise(i, j)) / r(i, j);
        const double g_abs = std::abs(g);
        if (g_abs > 1) g /= g_abs;
        phat(i, j) *= g;
        phat(j, i) = std::conj(phat(i, j));
      }
  }
  return out;
}

// ---------------------------------------------------------------- search

namespace {

struct Grid {
  std::vector<double> az, el;  // radians (1-D: az holds theta)
  bool wrap_az = true;
};

Grid MakeGrid(const SearchOptions& o) {
  Grid g;
  const double step = DegToRad(o.coarse_step_deg);
  if (o.kind == DoaKind::kAngle1d) {
    g.wrap_az = false;
    const int n = static_cast<int>(std::floor(M_PI / step + 1e-9)) + 1;
    for (int i = 0; i < n; ++i) g.az.push_back(std::min(M_PI, i * step));
    g.el = {0.0};
    return g;
  }
  const int n = static_cast<int>(std::round(2 * M_PI / step));
  for (int i = 0; i < n; ++i) g.az.push_back(-M_PI + i * 2 * M_PI / n);
  if (o.kind == DoaKind::kAzimuth) {
    g.el = {0.0};
  } else {
    const double lo = DegToRad(o.min_elevation_deg), hi = DegToRad(o.max_elevation_deg);
    const int ne = std::max(1, static_cast<int>(std::floor((hi - lo) / step + 1e-9)) + 1);
    for (int i = 0; i < ne; ++i) g.el.push_back(lo + i * step);
  }
  return g;
}

}  // namespace

std::vector<Eigen::Vector3d> SearchGridUnits(const ArrayGeometry& geometry,
                                             const SearchOptions& o) {
  const Grid grid = MakeGrid(o);
  std::vector<Eigen::Vector3d> units;
  units.reserve(grid.az.size() * grid.el.size());
  for (double el : grid.el)
    for (double az : grid.az) units.push_back(geometry.Unit(o.kind, {az, el}));
  return units;
}

std::vector<DoaEstimate> FindPeaks(const ArrayGeometry& geometry, const SearchOptions& o,
                                   const SpatialSpectrum& spectrum, double* grid_mean) {
  const std::vector<Eigen::Vector3d> units = SearchGridUnits(geometry, o);
  std::vector<double> values(units.size());
  for (size_t i = 0; i < units.size(); ++i) values[i] = spectrum(units[i]);
  return FindPeaksOnGrid(geometry, o, values, spectrum, grid_mean);
}

std::vector<DoaEstimate> FindPeaksOnGrid(const ArrayGeometry& geometry, const SearchOptions& o,
                                         const std::vector<double>& values,
                                         const SpatialSpectrum& spectrum, double* grid_mean) {
  const Grid grid = MakeGrid(o);
  const int na = static_cast<int>(grid.az.size()), ne = static_cast<int>(grid.el.size());
  if (values.size() != static_cast<size_t>(na) * ne)
    throw std::invalid_argument("grid values do not fit the search grid");
  double vmin = INFINITY, vmax = -INFINITY, sum = 0;
  for (double v : values) {
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
    sum += v;
  }
  if (grid_mean) *grid_mean = sum / values.size();
  if (!std::isfinite(vmax)) return {};
  struct Candidate {
    double value;
    Direction dir;
  };
  std::vector<Candidate> candidates;
  for (int e = 0; e < ne; ++e)
    for (int a = 0; a < na; ++a) {
      const double v = values[e * na + a];
      bool is_max = true;
      for (int de = -1; de <= 1 && is_max; ++de)
        for (int da = -1; da <= 1 && is_max; ++da) {
          if (!de && !da) continue;
          const int ee = e + de;
          int aa = a + da;
          if (ee < 0 || ee >= ne) continue;
          if (grid.wrap_az)
            aa = (aa + na) % na;
          else if (aa < 0 || aa >= na)
            continue;
          if (values[ee * na + aa] > v) is_max = false;
        }
      if (is_max) candidates.push_back({v, {grid.az[a], grid.el[e]}});
    }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& x, const Candidate& y) { return x.value > y.value; });

  const double lo_el = DegToRad(o.min_elevation_deg), hi_el = DegToRad(o.max_elevation_deg);
  auto refine = [&](Direction d, double v) {
    double step = DegToRad(o.coarse_step_deg) / 2;
    const double fine = DegToRad(o.fine_step_deg);
    while (step >= fine * 0.999) {
      for (int iter = 0; iter < 4; ++iter) {
        Direction best = d;
        double best_v = v;
        for (int de = -1; de <= 1; ++de)
          for (int da = -1; da <= 1; ++da) {
            if (!de && !da) continue;
            if (o.kind != DoaKind::kAzimuthElevation && de) continue;
            Direction t{d.azimuth_rad + da * step, d.elevation_rad + de * step};
            if (o.kind == DoaKind::kAngle1d)
              t.azimuth_rad = std::clamp(t.azimuth_rad, 0.0, M_PI);
            else
              t.azimuth_rad = WrapAngle(t.azimuth_rad);
            if (o.kind == DoaKind::kAzimuthElevation)
              t.elevation_rad = std::clamp(t.elevation_rad, lo_el, hi_el);
            const double tv = spectrum(geometry.Unit(o.kind, t));
            if (tv > best_v) {
              best_v = tv;
              best = t;
            }
          }
        if (best_v <= v) break;
        d = best;
        v = best_v;
      }
      step /= 2;
    }
    return Candidate{v, d};
  };

  std::vector<DoaEstimate> out;
  const double min_sep = DegToRad(o.min_separation_deg);
  const double range = std::max(vmax - vmin, 1e-12);
  for (const Candidate& c : candidates) {
    if (static_cast<int>(out.size()) >= o.max_sources) break;
    if (!out.empty() && (c.value - vmin) / range < o.min_peak_ratio) break;
    bool far = true;
    for (const auto& e : out)
      if (AngularDistanceRad(geometry, o.kind, e.direction, c.dir) < min_sep) far = false;
    if (!far) continue;
    const Candidate r = refine(c.dir, c.value);
    for (const auto& e : out)
      if (AngularDistanceRad(geometry, o.kind, e.direction, r.dir) < min_sep) far = false;
    if (!far) continue;
    DoaEstimate est;
    est.direction = r.dir;
    est.power = r.value;
    out.push_back(est);
  }
  return out;
}

// ---------------------------------------------------------------- steering

SteeredQuadraticForm::SteeredQuadraticForm(const ArrayGeometry& geometry,
                                           const BlockStatistics& stats)
    : geometry_(geometry), stats_(stats) {}

void SteeredQuadraticForm::Evaluate(const Eigen::Vector3d& u,
                                    const std::vector<Eigen::MatrixXcd>& q, bool off_diagonal_only,
                                    std::vector<double>* out) const {
  const int m = geometry_.num_mics();
  const Eigen::VectorXd tau = geometry_.Delays(u);
  const double dw = 2 * M_PI * stats_.sample_rate_hz / stats_.fft_size;
  ComplexD a[16], step[16];
  if (m > 16) throw std::invalid_argument("at most 16 microphones");
  for (int i = 0; i < m; ++i) {
    a[i] = std::polar(1.0, -dw * stats_.bin_lo * tau(i));
    step[i] = std::polar(1.0, -dw * tau(i));
  }
  const int nb = stats_.num_bins();
  out->resize(nb);
  for (int k = 0; k < nb; ++k) {
    const Eigen::MatrixXcd& Q = q[k];
    ComplexD acc = 0;
    for (int i = 0; i < m; ++i) {
      ComplexD row = 0;
      for (int j = i + 1; j < m; ++j) row += Q(i, j) * a[j];
      acc += std::conj(a[i]) * row;
    }
    double total = 2 * acc.real();
    if (!off_diagonal_only)
      for (int i = 0; i < m; ++i) total += Q(i, i).real();
    (*out)[k] = total;
    for (int i = 0; i < m; ++i) a[i] *= step[i];
  }
}

SrpPhat::SrpPhat(const ArrayGeometry& geometry, const BlockStatistics& stats)
    : form_(geometry, stats), stats_(stats) {
  const int m = geometry.num_mics();
  scale_ = 1.0 / (std::max(1, stats.num_frames) * std::max(1, stats.num_bins()) * m * (m - 1));
}

double SrpPhat::operator()(const Eigen::Vector3d& u) const {
  form_.Evaluate(u, stats_.phat, true, &per_bin_);
  return std::accumulate(per_bin_.begin(), per_bin_.end(), 0.0) * scale_;
}

CorrelationSrp::CorrelationSrp(const ArrayGeometry& geometry, int fft_size, int bin_lo, int bin_hi,
                               double lag_step_samples)
    : geometry_(geometry), bin_lo_(bin_lo), bin_hi_(bin_hi), lag_step_(lag_step_samples) {
  const int m = geometry.num_mics();
  for (int i = 0; i < m; ++i)
    for (int j = i + 1; j < m; ++j) pairs_.emplace_back(i, j);
  // Largest |tau_i - tau_j| in samples, plus a margin for interpolation.
  max_lag_ =
      geometry.aperture_m() / geometry.speed_of_sound_mps * geometry.sample_rate_hz + 2 * lag_step_;
  num_lags_ = 2 * static_cast<int>(std::ceil(max_lag_ / lag_step_)) + 1;
  const int nb = bin_hi - bin_lo + 1;
  cos_.resize(num_lags_, nb);
  sin_.resize(num_lags_, nb);
  const int half = num_lags_ / 2;
  for (int l = 0; l < num_lags_; ++l)
    for (int k = 0; k < nb; ++k) {
      const double phase = 2 * M_PI * (bin_lo + k) / fft_size * (l - half) * lag_step_;
      cos_(l, k) = std::cos(phase);
      sin_(l, k) = std::sin(phase);
    }
  corr_.assign(pairs_.size(), Eigen::VectorXd::Zero(num_lags_));
  magnitude_.assign(pairs_.size(), Eigen::VectorXd::Zero(nb));
  for (int k = 0; k < nb; ++k) bin_omega_.push_back(2 * M_PI * (bin_lo + k) / fft_size);
}

void CorrelationSrp::SetBlock(const BlockStatistics& stats) {
  if (stats.bin_lo != bin_lo_ || stats.bin_hi != bin_hi_)
    throw std::invalid_argument("CorrelationSrp: band differs");
  const int nb = num_bins();
  const double scale = 1.0 / (std::max(1, stats.num_frames) * std::max(1, nb));
  Eigen::VectorXd re(nb), im(nb);
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const auto [i, j] = pairs_[p];
    for (int k = 0; k < nb; ++k) {
      re(k) = stats.phat[k](i, j).real();
      im(k) = stats.phat[k](i, j).imag();
    }
    // Re(Q e^{j w d}) = Re Q cos(w d) - Im Q sin(w d)
    corr_[p].noalias() = (cos_ * re - sin_ * im) * scale;
    magnitude_[p] = (re.array().square() + im.array().square()).sqrt() * scale;
  }
}

double CorrelationSrp::PairValue(int p, double lag_samples) const {
  const double x = lag_samples / lag_step_ + num_lags_ / 2;
  const int i = std::clamp(static_cast<int>(std::floor(x)), 0, num_lags_ - 2);
  const double f = std::clamp(x - i, 0.0, 1.0);
  return (1 - f) * corr_[p](i) + f * corr_[p](i + 1);
}

double CorrelationSrp::operator()(const Eigen::Vector3d& u) const {
  const Eigen::VectorXd tau = geometry_.Delays(u) * geometry_.sample_rate_hz;
  double sum = 0;
  for (size_t p = 0; p < pairs_.size(); ++p)
    sum += PairValue(p, tau(pairs_[p].first) - tau(pairs_[p].second));
  return sum / pairs_.size();
}

void CorrelationSrp::Subtract(const Eigen::Vector3d& u) {
  const Eigen::VectorXd tau = geometry_.Delays(u) * geometry_.sample_rate_hz;
  const int nb = num_bins();
  Eigen::VectorXd c(nb), s(nb);
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const double d0 = tau(pairs_[p].first) - tau(pairs_[p].second);
    const double total = magnitude_[p].sum();  // h(0)
    if (total <= 0) continue;
    const double gain = std::clamp(PairValue(p, d0) / total, 0.0, 1.0);
    if (gain <= 0) continue;
    for (int k = 0; k < nb; ++k) {
      c(k) = magnitude_[p](k) * std::cos(bin_omega_[k] * d0);
      s(k) = magnitude_[p](k) * std::sin(bin_omega_[k] * d0);
    }
    // h(d - d0) = sum_k A_k (cos w d cos w d0 + sin w d sin w d0)
    // Only the kernel's positive lobes: subtracting its negative ones would raise false peaks
    // wherever the block's correlation is not exactly one plane wave's.
    corr_[p].noalias() -= gain * (cos_ * c + sin_ * s).cwiseMax(0.0);
    magnitude_[p] *= 1 - gain;
  }
}

void CorrelationSrp::PrepareGrid(const std::vector<Eigen::Vector3d>& units) {
  grid_pos_.assign(units.size(), std::vector<float>(pairs_.size()));
  for (size_t g = 0; g < units.size(); ++g) {
    const Eigen::VectorXd tau = geometry_.Delays(units[g]) * geometry_.sample_rate_hz;
    for (size_t p = 0; p < pairs_.size(); ++p)
      grid_pos_[g][p] = static_cast<float>(
          (tau(pairs_[p].first) - tau(pairs_[p].second)) / lag_step_ + num_lags_ / 2);
  }
}

void CorrelationSrp::EvaluateGrid(std::vector<double>* values) const {
  values->resize(grid_pos_.size());
  const double inv = 1.0 / pairs_.size();
  for (size_t g = 0; g < grid_pos_.size(); ++g) {
    double sum = 0;
    for (size_t p = 0; p < pairs_.size(); ++p) {
      const float x = grid_pos_[g][p];
      const int i = std::clamp(static_cast<int>(x), 0, num_lags_ - 2);
      const double f = x - i;
      sum += (1 - f) * corr_[p](i) + f * corr_[p](i + 1);
    }
    (*values)[g] = sum * inv;
  }
}

void CorrelationSrp::Suppress(const Eigen::Vector3d& u, double half_width_samples) {
  const Eigen::VectorXd tau = geometry_.Delays(u) * geometry_.sample_rate_hz;
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const double centre =
        (tau(pairs_[p].first) - tau(pairs_[p].second)) / lag_step_ + num_lags_ / 2;
    const double w = half_width_samples / lag_step_;
    const int lo = std::max(0, static_cast<int>(std::floor(centre - w)));
    const int hi = std::min(num_lags_ - 1, static_cast<int>(std::ceil(centre + w)));
    for (int l = lo; l <= hi; ++l) corr_[p](l) = 0;
  }
}

BandSrpPhat::BandSrpPhat(const ArrayGeometry& geometry, const BlockStatistics& stats,
                         double band_hz)
    : form_(geometry, stats), stats_(stats) {
  const int m = geometry.num_mics();
  const int nb = stats.num_bins();
  broadband_scale_ = 1.0 / (std::max(1, stats.num_frames) * std::max(1, nb) * m * (m - 1));
  const double bin_hz = static_cast<double>(stats.sample_rate_hz) / stats.fft_size;
  const int per_band = std::max(1, static_cast<int>(std::round(band_hz / bin_hz)));
  for (int k = 0; k < nb; k += per_band) band_first_.push_back(k);
  // A last band shorter than half a band joins the one before it.
  if (band_first_.size() > 1 && nb - band_first_.back() < per_band / 2) band_first_.pop_back();
  band_first_.push_back(nb);
  bin_weight_.assign(nb, 0.0);
  tonality_.assign(band_first_.size() - 1, 0.0);
  for (int b = 0; b + 1 < static_cast<int>(band_first_.size()); ++b) {
    double total_power = 0;
    std::vector<double> powers;
    for (int k = band_first_[b]; k < band_first_[b + 1]; ++k) {
      powers.push_back(std::max(0.0, stats.raw[k].trace().real()));
      total_power += powers.back();
    }
    if (total_power <= 0) continue;
    const size_t top = std::min<size_t>(3, powers.size());
    std::partial_sort(powers.begin(), powers.begin() + top, powers.end(), std::greater<>());
    tonality_[b] = std::accumulate(powers.begin(), powers.begin() + top, 0.0) / total_power;
    for (int k = band_first_[b]; k < band_first_[b + 1]; ++k) {
      const double frames =
          stats.phat[k].trace().real() / m;  // n_k: each frame adds |y_i|^2 = 1 per mic
      if (frames <= 0) continue;
      bin_weight_[k] =
          std::max(0.0, stats.raw[k].trace().real()) / total_power / (frames * m * (m - 1));
    }
  }
}

double BandSrpPhat::band_centre_hz(int b) const {
  const double bin_hz = static_cast<double>(stats_.sample_rate_hz) / stats_.fft_size;
  return (stats_.bin_lo + 0.5 * (band_first_[b] + band_first_[b + 1] - 1)) * bin_hz;
}

double BandSrpPhat::Evaluate(const Eigen::Vector3d& u, std::vector<double>* bands) const {
  form_.Evaluate(u, stats_.phat, true, &per_bin_);
  double total = 0;
  for (double v : per_bin_) total += v;
  if (bands) {
    bands->assign(num_bands(), 0.0);
    for (int b = 0; b < num_bands(); ++b)
      for (int k = band_first_[b]; k < band_first_[b + 1]; ++k)
        (*bands)[b] += bin_weight_[k] * per_bin_[k];
  }
  return total * broadband_scale_;
}

double BandSrpPhat::Band(const Eigen::Vector3d& u, int b) const {
  form_.Evaluate(u, stats_.phat, true, &per_bin_);
  double value = 0;
  for (int k = band_first_[b]; k < band_first_[b + 1]; ++k) value += bin_weight_[k] * per_bin_[k];
  return value;
}

Music::Music(const ArrayGeometry& geometry, const BlockStatistics& stats, int num_sources,
             bool generalized)
    : form_(geometry, stats), num_mics_(geometry.num_mics()) {
  const int m = num_mics_;
  const int d = std::clamp(num_sources, 1, m - 1);
  const int nb = stats.num_bins();
  noise_projectors_.resize(nb);
  weights_.resize(nb);
  used_generalized_ = generalized && static_cast<int>(stats.noise.size()) == nb;
  for (int k = 0; k < nb; ++k) {
    const Eigen::MatrixXcd& R = stats.raw[k];
    Eigen::MatrixXcd En;
    double top = 0;
    if (used_generalized_) {
      Eigen::MatrixXcd K = stats.noise[k];
      const double load = std::max(1e-12, 1e-3 * K.trace().real() / m);
      K += load * Eigen::MatrixXcd::Identity(m, m);
      Eigen::LLT<Eigen::MatrixXcd> llt(K);
      const Eigen::MatrixXcd L = llt.matrixL();
      const Eigen::MatrixXcd Linv = L.inverse();
      const Eigen::MatrixXcd C = Linv * R * Linv.adjoint();
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(0.5 * (C + C.adjoint()));
      En = Linv.adjoint() * eig.eigenvectors().leftCols(m - d);
      for (int c = 0; c < En.cols(); ++c) En.col(c).normalize();
      top = std::max(0.0, eig.eigenvalues()(m - 1));
    } else {
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(0.5 * (R + R.adjoint()));
      En = eig.eigenvectors().leftCols(m - d);
      top = std::max(0.0, eig.eigenvalues()(m - 1));
    }
    noise_projectors_[k] = En * En.adjoint();
    weights_[k] = std::sqrt(top);
  }
  const double total = std::accumulate(weights_.begin(), weights_.end(), 0.0);
  for (double& w : weights_) w = total > 0 ? w / total : 1.0 / nb;
}

double Music::operator()(const Eigen::Vector3d& u) const {
  form_.Evaluate(u, noise_projectors_, false, &per_bin_);
  double p = 0;
  for (size_t k = 0; k < per_bin_.size(); ++k)
    p += weights_[k] / std::max(per_bin_[k] / num_mics_, 1e-4);
  return p;
}

// ---------------------------------------------------------------- GCC-PHAT

double GccPhatTdoa(const BlockStatistics& stats, int i, int j, double max_tau_s, int upsample,
                   double* peak) {
  const double fs = stats.sample_rate_hz;
  const int max_lag = static_cast<int>(std::ceil(max_tau_s * fs * upsample)) + 1;
  const double dw = 2 * M_PI * fs / stats.fft_size;
  std::vector<double> r(2 * max_lag + 1);
  for (int l = -max_lag; l <= max_lag; ++l) {
    const double t = static_cast<double>(l) / (fs * upsample);
    double s = 0;
    for (int k = 0; k < stats.num_bins(); ++k) {
      const ComplexD g = stats.phat[k](i, j);
      const double ph = dw * (stats.bin_lo + k) * t;
      s += g.real() * std::cos(ph) - g.imag() * std::sin(ph);
    }
    r[l + max_lag] = s;
  }
  const int best = static_cast<int>(std::max_element(r.begin(), r.end()) - r.begin());
  double offset = 0;
  if (best > 0 && best + 1 < static_cast<int>(r.size())) {
    const double y0 = r[best - 1], y1 = r[best], y2 = r[best + 1];
    const double den = y0 - 2 * y1 + y2;
    if (den < 0) offset = 0.5 * (y0 - y2) / den;
  }
  if (peak) *peak = r[best] / std::max(1, stats.num_frames * stats.num_bins());
  return (best - max_lag + offset) / (fs * upsample);
}

std::vector<DoaEstimate> GccPhatDirection(const ArrayGeometry& g, const BlockStatistics& stats,
                                          DoaKind kind) {
  const int m = g.num_mics();
  const int pairs = m * (m - 1) / 2;
  Eigen::MatrixXd D(pairs, 3);
  Eigen::VectorXd b(pairs), w(pairs);
  int row = 0;
  double mean_peak = 0;
  for (int i = 0; i < m; ++i)
    for (int j = i + 1; j < m; ++j, ++row) {
      const Eigen::Vector3d dp = g.positions_m.col(i) - g.positions_m.col(j);
      double peak = 0;
      const double tau = GccPhatTdoa(stats, i, j, dp.norm() / g.speed_of_sound_mps * 1.1, 8, &peak);
      D.row(row) = dp.transpose();
      b(row) = -g.speed_of_sound_mps * tau;
      w(row) = std::max(peak, 1e-3);
      mean_peak += peak / pairs;
    }
  const Eigen::MatrixXd Dw = w.asDiagonal() * D;
  const Eigen::VectorXd bw = w.asDiagonal() * b;
  Eigen::Vector3d u;
  if (g.is_linear()) {
    const Eigen::VectorXd da = Dw * g.axis;
    const double c = std::clamp(da.dot(bw) / std::max(da.squaredNorm(), 1e-12), -1.0, 1.0);
    u = c * g.axis + std::sqrt(1 - c * c) * g.axis.unitOrthogonal();
  } else if (g.geometry == "planar") {
    const Eigen::Vector3d e1 = g.normal.unitOrthogonal(), e2 = g.normal.cross(e1);
    Eigen::MatrixXd P(3, 2);
    P << e1, e2;
    const Eigen::Vector2d v = (Dw * P).colPivHouseholderQr().solve(bw);
    const double n2 = v.squaredNorm();
    const Eigen::Vector2d vin = n2 > 1 ? Eigen::Vector2d(v / std::sqrt(n2)) : v;
    u = P * vin + std::sqrt(std::max(0.0, 1 - vin.squaredNorm())) * g.normal;
  } else {
    u = Dw.colPivHouseholderQr().solve(bw);
    if (u.norm() < 1e-9) u = Eigen::Vector3d::UnitX();
    u.normalize();
  }
  DoaEstimate e;
  e.direction = g.FromUnit(kind, u);
  e.power = mean_peak;
  e.confidence = std::clamp(mean_peak, 0.0, 1.0);
  return {e};
}

// ---------------------------------------------------------------- ESPRIT

std::vector<DoaEstimate> Esprit(const ArrayGeometry& g, const BlockStatistics& stats,
                                int num_sources, double min_separation_deg) {
  const double d = g.UniformSpacing();
  if (!g.is_linear() || d <= 0 || g.num_mics() < 3)
    throw std::invalid_argument("ESPRIT needs a uniform linear array of >= 3 microphones; '" +
                                g.name + "' is not one");
  const int m = g.num_mics();
  const int ns = std::clamp(num_sources, 1, m - 2);
  const double f_max = g.speed_of_sound_mps / (2 * d);
  // Histogram of angles to the axis, 0.5 deg bins, weighted by the signal eigenvalue.
  const int nh = 361;
  std::vector<double> hist(nh, 0.0);
  std::vector<std::pair<double, double>> samples;  // (theta, weight)
  for (int k = 0; k < stats.num_bins(); ++k) {
    const double f = stats.BinHz(stats.bin_lo + k);
    if (f > f_max || f < 200) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(0.5 *
                                                        (stats.raw[k] + stats.raw[k].adjoint()));
    const Eigen::MatrixXcd Es = eig.eigenvectors().rightCols(ns);
    const Eigen::MatrixXcd E1 = Es.topRows(m - 1), E2 = Es.bottomRows(m - 1);
    const Eigen::MatrixXcd Phi = E1.colPivHouseholderQr().solve(E2);
    Eigen::ComplexEigenSolver<Eigen::MatrixXcd> ces(Phi);
    for (int s = 0; s < ns; ++s) {
      const double phase = std::arg(ces.eigenvalues()(s));
      const double c = phase * g.speed_of_sound_mps / (2 * M_PI * f * d);
      if (std::abs(c) > 1.05) continue;
      const double theta = std::acos(std::clamp(c, -1.0, 1.0));
      const double w = std::sqrt(std::max(0.0, eig.eigenvalues()(m - ns + s)));
      samples.emplace_back(theta, w);
      const int bin = static_cast<int>(std::round(RadToDeg(theta) * 2));
      for (int b = std::max(0, bin - 4); b <= std::min(nh - 1, bin + 4); ++b)
        hist[b] += w * (1.0 - std::abs(b - bin) / 5.0);
    }
  }
  std::vector<DoaEstimate> out;
  std::vector<bool> used(nh, false);
  const double total = std::accumulate(hist.begin(), hist.end(), 0.0);
  for (int s = 0; s < num_sources && total > 0; ++s) {
    int best = -1;
    for (int b = 0; b < nh; ++b)
      if (!used[b] && (best < 0 || hist[b] > hist[best])) best = b;
    if (best < 0 || hist[best] <= 0) break;
    if (!out.empty() && hist[best] < 0.3 * out.front().power) break;
    // Refine: weighted mean of the samples within 3 deg.
    const double centre = DegToRad(best / 2.0);
    double sw = 0, st = 0;
    for (const auto& [t, w] : samples)
      if (std::abs(t - centre) < DegToRad(3)) {
        sw += w;
        st += w * t;
      }
    DoaEstimate e;
    e.direction.azimuth_rad = sw > 0 ? st / sw : centre;
    e.power = hist[best];
    e.confidence = std::clamp(hist[best] / total * 10, 0.0, 1.0);
    out.push_back(e);
    const int sep = static_cast<int>(min_separation_deg * 2);
    for (int b = std::max(0, best - sep); b <= std::min(nh - 1, best + sep); ++b) used[b] = true;
  }
  return out;
}

}  // namespace sound
}  // namespace sarmap
