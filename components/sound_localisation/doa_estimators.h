#pragma once
// Direction-of-arrival estimators on per-bin spatial covariance matrices of one analysis
// block (no LCM).
//
// Per frequency bin k (angular frequency w_k) the block statistics are
//   R(k)      = mean_t X_t(k) X_t(k)^H                       (raw, for MUSIC)
//   Rphat(k)  = mean_t Y_t(k) Y_t(k)^H, Y_m = X_m / |X_m|     (PHAT-whitened, for SRP)
//   K(k)      = noise covariance learnt from non-speech frames (for GEVD-MUSIC)
// SRP-PHAT:   P(u) = sum_k sum_{i<j} 2 Re(Rphat_ij(k) exp(j w_k (tau_i(u) - tau_j(u))))
//             (the steered response power of the phase-transformed signals, constant diagonal
//             dropped); divided by (#bins * #pairs) it is the mean PHAT coherence, in [-1, 1].
// MUSIC:      per bin, eigenvectors of R (SEVD) or of the pencil (R, K) (GEVD: R v = l K v);
//             the M - d weakest span the noise subspace En(k), orthogonal to the steering
//             vectors a_k(u) of the d sources. Broadband pseudo-spectrum (incoherent sum):
//             P(u) = sum_k w_k / max(|En(k)^H a_k(u)|^2 / M, floor), w_k = sqrt(l_max(k)) / sum.
// GCC-PHAT:   tau_ij = argmax_tau IFFT(Rphat_ij)(tau) per pair (with sub-sample interpolation),
//             then the far-field direction by least squares: (p_i - p_j) . u = -c tau_ij.
// ESPRIT:     uniform linear arrays: per bin, the rotation between the two overlapping
//             sub-arrays of the signal subspace, Es2 = Es1 Phi, has eigenvalues
//             exp(-j w_k d cos(theta) / c); angles from all bins are pooled and clustered.

#include <Eigen/Core>
#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "sound_localisation/array_geometry.h"

namespace sarmap {
namespace sound {

using ComplexD = std::complex<double>;

// Statistics of one block over the analysed band [bin_lo, bin_hi].
struct BlockStatistics {
  int fft_size = 512;
  int sample_rate_hz = 16000;
  int bin_lo = 0, bin_hi = 0;
  int num_frames = 0;                   // active frames accumulated
  std::vector<Eigen::MatrixXcd> raw;    // R(k), index k - bin_lo
  std::vector<Eigen::MatrixXcd> phat;   // Rphat(k)
  std::vector<Eigen::MatrixXcd> noise;  // K(k) (empty if unknown)
  int num_bins() const { return bin_hi - bin_lo + 1; }
  double BinHz(int k) const { return static_cast<double>(k) * sample_rate_hz / fft_size; }
  void Reset(int num_mics);
  void Add(const BlockStatistics& other);  // sums (same shape)
};

// SRP-PHAT with the noise's cross-spectra removed. A steady interferer (a phone's music, an
// engine) adds its own cross-spectrum to every bin that a voice also fills, and on a small
// array the two peaks merge: the voice's peak is bent off its bearing. With the
// noise covariance K(k) learnt from the frames between sounds, per bin and pair
//   S_ij(k) = R_ij(k) - beta n_k K_ij(k)       (the block's cross-power not explained by noise),
//   Rphat_ij(k) <- Rphat_ij(k) g,  g = S_ij / R_ij with |g| clipped to 1,
// so each PHAT cross-term turns by the phase the noise added and shrinks by the share of the
// cross-power that was noise (n_k: frames holding bin k). Returns stats unchanged when no noise
// is known.
BlockStatistics SubtractNoiseCrossSpectra(const BlockStatistics& stats, double beta);

// A direction found by an estimator, before tracking.
struct DoaEstimate {
  Direction direction;
  double power = 0;       // spectrum value at the peak (method units)
  double confidence = 0;  // 0..1
  int band = -1;          // BandSrpPhat band that found it; -1: the broadband spectrum
  double band_hz = 0;     // that band's centre frequency
};

struct SearchOptions {
  DoaKind kind = DoaKind::kAzimuthElevation;
  double coarse_step_deg = 5.0;
  double fine_step_deg = 0.25;
  double min_elevation_deg = 0.0;
  double max_elevation_deg = 90.0;
  int max_sources = 1;
  double min_separation_deg = 20.0;
  // A secondary peak must reach this fraction of the best one, on the spectrum scaled to
  // [grid minimum, best] (0..1).
  double min_peak_ratio = 0.5;
};

// A spatial spectrum over directions (higher = more likely a source).
using SpatialSpectrum = std::function<double(const Eigen::Vector3d& u)>;

// Coarse grid, local maxima with suppression of close ones, then hill-climbing refinement
// with halving steps down to fine_step_deg. Returned best first; `grid_mean` (optional)
// gets the spectrum's mean over the coarse grid.
std::vector<DoaEstimate> FindPeaks(const ArrayGeometry& geometry, const SearchOptions& options,
                                   const SpatialSpectrum& spectrum, double* grid_mean = nullptr);
// The coarse grid's directions (unit vectors), in the order FindPeaksOnGrid expects values.
std::vector<Eigen::Vector3d> SearchGridUnits(const ArrayGeometry& geometry,
                                             const SearchOptions& options);
// FindPeaks on spectrum values already computed at SearchGridUnits; `spectrum` refines.
std::vector<DoaEstimate> FindPeaksOnGrid(const ArrayGeometry& geometry,
                                         const SearchOptions& options,
                                         const std::vector<double>& values,
                                         const SpatialSpectrum& spectrum,
                                         double* grid_mean = nullptr);

// Per-bin quadratic forms a_k(u)^H Q_k a_k(u) (real parts) for steering vectors of u.
class SteeredQuadraticForm {
 public:
  SteeredQuadraticForm(const ArrayGeometry& geometry, const BlockStatistics& stats);
  // out[k - bin_lo] = a^H Q[k - bin_lo] a; off_diagonal_only drops the i == j terms.
  void Evaluate(const Eigen::Vector3d& u, const std::vector<Eigen::MatrixXcd>& q,
                bool off_diagonal_only, std::vector<double>* out) const;

 private:
  const ArrayGeometry& geometry_;
  const BlockStatistics& stats_;
};

class SrpPhat {
 public:
  SrpPhat(const ArrayGeometry& geometry, const BlockStatistics& stats);
  double operator()(const Eigen::Vector3d& u) const;  // mean PHAT coherence
 private:
  SteeredQuadraticForm form_;
  const BlockStatistics& stats_;
  double scale_;
  mutable std::vector<double> per_bin_;
};

// SRP-PHAT through each pair's PHAT cross-correlation (as ODAS and HARK compute it): per block
//   r_ij(d) = sum_k Re(Rphat_ij(k) e^{j w_k d}) / (N K)     on a lag grid d (lag_step samples),
//   P(u)    = mean over pairs of r_ij(tau_i(u) - tau_j(u))  (linear interpolation between lags),
// which is SrpPhat's value up to the interpolation (1/32 sample: < 0.1 % at 7 kHz). The lag
// pass costs pairs x lags x bins once per block; every direction afterwards costs one lookup per
// pair, so the whole grid and the refinement are cheap. Suppress() zeroes each pair's
// correlation around a found direction's lag, so the next search finds the next source and not
// the found one's lobe.
class CorrelationSrp {
 public:
  CorrelationSrp(const ArrayGeometry& geometry, int fft_size, int bin_lo, int bin_hi,
                 double lag_step_samples = 1.0 / 32);
  void SetBlock(const BlockStatistics& stats);  // same fft_size and band
  double operator()(const Eigen::Vector3d& u) const;
  // Values at the given directions (grid), through lag indices precomputed by PrepareGrid.
  void PrepareGrid(const std::vector<Eigen::Vector3d>& units);
  void EvaluateGrid(std::vector<double>* values) const;
  // Zero every pair's correlation within +-half_width_samples of u's lag.
  void Suppress(const Eigen::Vector3d& u, double half_width_samples);
  // CLEAN: removes a plane wave from u from every pair's correlation, main lobe and side and
  // grating lobes alike. A single source's cross term is A_k e^{-j w_k d0}, so its correlation
  // is h(d - d0) with h(d) = sum_k A_k cos(w_k d); A_k is taken as |Rphat_ij(k)| and the
  // kernel scaled to the pair's value at d0 (at most the whole kernel).
  void Subtract(const Eigen::Vector3d& u);
  int num_pairs() const { return static_cast<int>(pairs_.size()); }
  int num_bins() const { return bin_hi_ - bin_lo_ + 1; }

 private:
  double PairValue(int p, double lag_samples) const;
  const ArrayGeometry& geometry_;
  int bin_lo_, bin_hi_;
  double lag_step_, max_lag_;
  int num_lags_;
  std::vector<std::pair<int, int>> pairs_;
  Eigen::MatrixXd cos_, sin_;                 // lags x bins
  std::vector<Eigen::VectorXd> corr_;         // per pair, per lag
  std::vector<Eigen::VectorXd> magnitude_;    // per pair, per bin: |Rphat_ij(k)| (scaled as corr_)
  std::vector<double> bin_omega_;             // rad per sample
  std::vector<std::vector<float>> grid_pos_;  // per grid direction, per pair: fractional lag index
};

// Narrowband sources (a ring tone, an alarm's harmonics) fill only a few bins. In the broadband
// SRP-PHAT sum every bin votes with the same weight, so broadband sources (voices, engines)
// win every direction vote while the tonal source is only heard in its own bins. Per band b
// of the analysed range (width band_hz), with the bins weighted by their power, the tonal
// bins dominate their band:
//   c_k(u) = sum_{i != j} Re(Rphat_ij(k) e^{j w_k (tau_i(u) - tau_j(u))}) / (n_k M (M - 1)),
//            the mean PHAT coherence of bin k over the n_k frames that hold it (in [-1, 1]),
//   P_b(u) = sum_{k in b} w_k c_k(u),   w_k = tr R(k) / sum_{k' in b} tr R(k').
// The broadband spectrum (SrpPhat's value) is sum_k n_k c_k / (N K) over all K bins of the
// N frames; Evaluate gives both from one steering pass.
class BandSrpPhat {
 public:
  BandSrpPhat(const ArrayGeometry& geometry, const BlockStatistics& stats, double band_hz);
  int num_bands() const { return static_cast<int>(band_first_.size()) - 1; }
  double band_centre_hz(int b) const;
  // Returns the broadband SRP-PHAT value (as SrpPhat); bands (optional) gets P_b(u) per band.
  double Evaluate(const Eigen::Vector3d& u, std::vector<double>* bands) const;
  double Band(const Eigen::Vector3d& u, int b) const;
  // Fraction of band b's power in its 3 strongest bins: a tone or two harmonics ~1, noise and
  // voiced speech (many harmonics per band) lower.
  double band_tonality(int b) const { return tonality_[b]; }

 private:
  SteeredQuadraticForm form_;
  const BlockStatistics& stats_;
  double broadband_scale_;
  std::vector<int>
      band_first_;  // band b holds bins [band_first_[b], band_first_[b + 1]) (index - bin_lo)
  std::vector<double> bin_weight_;  // w_k / (n_k M (M - 1)): per-bin value -> weighted coherence
  std::vector<double> tonality_;
  mutable std::vector<double> per_bin_;
};

class Music {
 public:
  // generalized: use the noise covariance (stats.noise must be set, else falls back to SEVD).
  Music(const ArrayGeometry& geometry, const BlockStatistics& stats, int num_sources,
        bool generalized);
  double operator()(const Eigen::Vector3d& u) const;
  bool used_generalized() const { return used_generalized_; }

 private:
  SteeredQuadraticForm form_;
  std::vector<Eigen::MatrixXcd> noise_projectors_;
  std::vector<double> weights_;
  int num_mics_;
  bool used_generalized_ = false;
  mutable std::vector<double> per_bin_;
};

// GCC-PHAT time difference of arrival tau_i - tau_j (seconds) for one pair from the block's
// PHAT cross-spectrum, searched within +-max_tau_s; `peak` gets the correlation value.
double GccPhatTdoa(const BlockStatistics& stats, int i, int j, double max_tau_s, int upsample,
                   double* peak = nullptr);
// Direction from all pairwise GCC-PHAT TDOAs (least squares), one source.
std::vector<DoaEstimate> GccPhatDirection(const ArrayGeometry& geometry,
                                          const BlockStatistics& stats, DoaKind kind);

// ESPRIT on a uniform linear array (throws std::invalid_argument otherwise). Up to
// max_sources angles to the axis, clustered from all bins below the spatial-aliasing limit.
std::vector<DoaEstimate> Esprit(const ArrayGeometry& geometry, const BlockStatistics& stats,
                                int num_sources, double min_separation_deg);

}  // namespace sound
}  // namespace sarmap
