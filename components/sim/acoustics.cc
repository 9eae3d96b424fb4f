#include "sim/acoustics.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sarmap {
namespace sim {

double EyringAbsorptionForRt60(double volume_m3, double surface_m2, double rt60_s) {
  return 1.0 - std::exp(-0.161 * volume_m3 / (surface_m2 * rt60_s));
}

double SabineAbsorptionForRt60(double volume_m3, double surface_m2, double rt60_s) {
  return std::min(1.0, 0.161 * volume_m3 / (surface_m2 * rt60_s));
}

double EyringRt60(double volume_m3, double surface_m2, double absorption) {
  if (absorption >= 1.0) return 0.0;
  return 0.161 * volume_m3 / (-surface_m2 * std::log(1.0 - absorption));
}

double SetUniformRt60(ShoeboxRoom* room, double rt60_s, double sample_rate_hz, double speed_of_sound_mps) {
  double alpha = EyringAbsorptionForRt60(room->Volume(), room->Surface(), rt60_s);
  room->beta.fill(std::sqrt(1.0 - alpha));
  RirOptions options;
  options.sample_rate_hz = sample_rate_hz;
  options.speed_of_sound_mps = speed_of_sound_mps;
  options.max_length_s = 1.1 * rt60_s;
  options.exact_order = 0;  // the decay does not need exact early delays
  const Eigen::Vector3d size = room->max - room->min;
  const Eigen::Vector3d source = room->min + size.cwiseProduct(Eigen::Vector3d(0.31, 0.43, 0.55));
  const Eigen::Vector3d mic = room->min + size.cwiseProduct(Eigen::Vector3d(0.67, 0.61, 0.37));
  double measured = 0;
  for (int iteration = 0; iteration < 8; ++iteration) {
    measured = SchroederRt60(ImageSourceRir(*room, source, mic, options), sample_rate_hz, -5, -25);
    if (measured <= 0 || std::abs(measured - rt60_s) < 0.02 * rt60_s) break;
    // Decay rate ~ -ln(1 - alpha): scale it by how much too slow (or fast) the decay is.
    const double log_keep = std::log(1.0 - alpha) * measured / rt60_s;
    alpha = std::clamp(1.0 - std::exp(log_keep), 1e-4, 0.999);
    room->beta.fill(std::sqrt(1.0 - alpha));
  }
  return measured;
}

void SetAbsorption(ShoeboxRoom* room, const std::vector<double>& absorption) {
  if (absorption.size() != 1 && absorption.size() != 6) {
    throw std::invalid_argument("absorption needs 1 or 6 values");
  }
  for (int k = 0; k < 6; ++k) {
    const double a = std::clamp(absorption.size() == 1 ? absorption[0] : absorption[k], 0.0, 1.0);
    room->beta[k] = std::sqrt(1.0 - a);
  }
}

void AddFractionalDelay(std::vector<float>* h, double delay_samples, double gain, int half_width) {
  const int centre = static_cast<int>(std::floor(delay_samples));
  const int first = centre - half_width + 1, last = centre + half_width;
  if (last < 0) return;
  if (static_cast<int>(h->size()) <= last) h->resize(last + 1, 0.0f);
  for (int n = std::max(0, first); n <= last; ++n) {
    const double x = n - delay_samples;
    const double sinc = std::abs(x) < 1e-9 ? 1.0 : std::sin(M_PI * x) / (M_PI * x);
    const double window = 0.5 * (1.0 + std::cos(M_PI * x / (half_width + 1)));
    (*h)[n] += static_cast<float>(gain * sinc * window);
  }
}

std::vector<float> ImageSourceRir(const ShoeboxRoom& room, const Eigen::Vector3d& source,
                                  const Eigen::Vector3d& mic, const RirOptions& options) {
  const double fs = options.sample_rate_hz, c = options.speed_of_sound_mps;
  const double max_dist = c * options.max_length_s;
  std::vector<float> h(static_cast<size_t>(std::ceil(options.max_length_s * fs)) +
                           options.sinc_half_width + 2, 0.0f);
  auto add = [&](double dist, double gain, bool exact) {
    const double r = std::max(dist, 0.05);
    const double delay = r / c * fs;
    if (exact) {
      AddFractionalDelay(&h, delay, gain / r, options.sinc_half_width);
    } else {  // late reflections: linear interpolation is plenty for a diffuse tail
      const int n = static_cast<int>(delay);
      const double f = delay - n;
      if (n + 1 < static_cast<int>(h.size())) {
        h[n] += static_cast<float>((1 - f) * gain / r);
        h[n + 1] += static_cast<float>(f * gain / r);
      }
    }
  };
  if (!options.reverb) {
    if (options.min_order == 0) add((source - mic).norm(), 1.0, true);
    return h;
  }
  // Per axis: the offsets of all images from the mic, with gain and reflection order.
  struct Axis {
    std::vector<double> offset, gain;
    std::vector<int> order;
  };
  const Eigen::Vector3d size = room.max - room.min;
  const Eigen::Vector3d s = source - room.min, m = mic - room.min;
  Axis axes[3];
  for (int a = 0; a < 3; ++a) {
    const double L = size[a];
    const int N = static_cast<int>(std::ceil(max_dist / (2 * L))) + 1;
    const double b_lo = room.beta[2 * a], b_hi = room.beta[2 * a + 1];
    for (int n = -N; n <= N; ++n) {
      for (int q = 0; q <= 1; ++q) {
        const double x = (1 - 2 * q) * s[a] + 2 * n * L;
        const int r_lo = std::abs(n - q), r_hi = std::abs(n);
        const double g = std::pow(b_lo, r_lo) * std::pow(b_hi, r_hi);
        if (g == 0.0 && (r_lo + r_hi) > 0) continue;
        const double off = x - m[a];
        if (std::abs(off) > max_dist || r_lo + r_hi > options.max_order) continue;
        axes[a].offset.push_back(off);
        axes[a].gain.push_back(r_lo + r_hi == 0 ? 1.0 : g);
        axes[a].order.push_back(r_lo + r_hi);
      }
    }
  }
  const double max_d2 = max_dist * max_dist;
  // Late images (order > exact_order): linear interpolation, in a tight loop.
  const float samples_per_m = static_cast<float>(fs / c);
  const int last_tap = static_cast<int>(h.size()) - 2;
  float* out = h.data();
  for (size_t i = 0; i < axes[0].offset.size(); ++i) {
    const double dx2 = axes[0].offset[i] * axes[0].offset[i];
    if (dx2 > max_d2) continue;
    for (size_t j = 0; j < axes[1].offset.size(); ++j) {
      const double dxy2 = dx2 + axes[1].offset[j] * axes[1].offset[j];
      if (dxy2 > max_d2) continue;
      const double gxy = axes[0].gain[i] * axes[1].gain[j];
      const int oxy = axes[0].order[i] + axes[1].order[j];
      const size_t nz = axes[2].offset.size();
      const double* oz = axes[2].offset.data();
      const double* gz = axes[2].gain.data();
      const int* ordz = axes[2].order.data();
      if (oxy > options.max_order) continue;
      for (size_t k = 0; k < nz; ++k) {
        const double d2 = dxy2 + oz[k] * oz[k];
        const int order = oxy + ordz[k];
        if (d2 > max_d2 || order < options.min_order || order > options.max_order) continue;
        const double g = gxy * gz[k];
        if (order <= options.exact_order) {
          add(std::sqrt(d2), g, true);
          continue;
        }
        const float r = std::max(static_cast<float>(std::sqrt(d2)), 0.05f);
        const float delay = r * samples_per_m;
        const int n = static_cast<int>(delay);
        if (n > last_tap) continue;
        const float f = delay - n, a = static_cast<float>(g) / r;
        out[n] += (1 - f) * a;
        out[n + 1] += f * a;
      }
    }
  }
  return h;
}

double SchroederRt60(const std::vector<float>& h, double sample_rate_hz, double from_db, double to_db) {
  const size_t n = h.size();
  std::vector<double> edc(n + 1, 0.0);
  for (size_t k = n; k-- > 0;) edc[k] = edc[k + 1] + static_cast<double>(h[k]) * h[k];
  if (edc[0] <= 0) return 0;
  // Least-squares line through the decay curve (dB) between from_db and to_db.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int count = 0;
  bool reached = false;
  for (size_t k = 0; k < n; ++k) {
    const double db = 10.0 * std::log10(std::max(edc[k] / edc[0], 1e-30));
    if (db > from_db) continue;
    if (db < to_db) {
      reached = true;
      break;
    }
    const double t = k / sample_rate_hz;
    sx += t;
    sy += db;
    sxx += t * t;
    sxy += t * db;
    ++count;
  }
  if (!reached || count < 10) return 0;
  const double slope = (count * sxy - sx * sy) / (count * sxx - sx * sx);  // dB per second
  return slope < 0 ? -60.0 / slope : 0;
}

struct MultiConvolver::Impl {
  int nfft = 0;
  double* time = nullptr;
  fftw_complex* freq = nullptr;
  fftw_complex* prod = nullptr;
  double* out = nullptr;
  fftw_plan forward = nullptr, inverse = nullptr;
  std::vector<std::vector<std::complex<double>>> filters, old_filters;
  std::vector<std::vector<double>> tails;
  bool crossfade = false;
  ~Impl() {
    fftw_destroy_plan(forward);
    fftw_destroy_plan(inverse);
    fftw_free(time);
    fftw_free(freq);
    fftw_free(prod);
    fftw_free(out);
  }
};

MultiConvolver::MultiConvolver(int block, int max_filter, int outputs)
    : impl_(std::make_unique<Impl>()), block_(block), max_filter_(max_filter), outputs_(outputs) {
  int nfft = 64;
  while (nfft < block + max_filter - 1) nfft *= 2;
  impl_->nfft = nfft;
  impl_->time = fftw_alloc_real(nfft);
  impl_->out = fftw_alloc_real(nfft);
  impl_->freq = fftw_alloc_complex(nfft / 2 + 1);
  impl_->prod = fftw_alloc_complex(nfft / 2 + 1);
  // FFTW_ESTIMATE: deterministic plans (no timing), so runs repeat bit for bit.
  impl_->forward = fftw_plan_dft_r2c_1d(nfft, impl_->time, impl_->freq, FFTW_ESTIMATE);
  impl_->inverse = fftw_plan_dft_c2r_1d(nfft, impl_->prod, impl_->out, FFTW_ESTIMATE);
  impl_->tails.assign(outputs, std::vector<double>(nfft - block, 0.0));
}

MultiConvolver::~MultiConvolver() = default;

void MultiConvolver::SetFilters(const std::vector<std::vector<float>>& filters) {
  if (static_cast<int>(filters.size()) != outputs_) throw std::invalid_argument("filter count");
  const int nfft = impl_->nfft;
  std::vector<std::vector<std::complex<double>>> spectra(outputs_);
  for (int o = 0; o < outputs_; ++o) {
    std::fill(impl_->time, impl_->time + nfft, 0.0);
    const int len = std::min<int>(static_cast<int>(filters[o].size()), max_filter_);
    for (int k = 0; k < len; ++k) impl_->time[k] = filters[o][k] / nfft;  // fold in 1/N of the inverse
    fftw_execute(impl_->forward);
    spectra[o].resize(nfft / 2 + 1);
    for (int k = 0; k <= nfft / 2; ++k) spectra[o][k] = {impl_->freq[k][0], impl_->freq[k][1]};
  }
  impl_->crossfade = has_filters_;
  impl_->old_filters = std::move(impl_->filters);
  impl_->filters = std::move(spectra);
  has_filters_ = true;
}

void MultiConvolver::Process(const float* input, const std::vector<float*>& out) {
  const int nfft = impl_->nfft, tail = nfft - block_;
  std::fill(impl_->time, impl_->time + nfft, 0.0);
  for (int k = 0; k < block_; ++k) impl_->time[k] = input[k];
  fftw_execute(impl_->forward);
  std::vector<double> y(nfft), y_old;
  for (int o = 0; o < outputs_; ++o) {
    auto convolve = [&](const std::vector<std::complex<double>>& H, std::vector<double>* dst) {
      for (int k = 0; k <= nfft / 2; ++k) {
        const std::complex<double> x(impl_->freq[k][0], impl_->freq[k][1]);
        const std::complex<double> p = x * H[k];
        impl_->prod[k][0] = p.real();
        impl_->prod[k][1] = p.imag();
      }
      fftw_execute(impl_->inverse);
      dst->assign(impl_->out, impl_->out + nfft);
    };
    convolve(impl_->filters[o], &y);
    if (impl_->crossfade) {
      convolve(impl_->old_filters[o], &y_old);
      for (int k = 0; k < block_; ++k) {
        const double w = (k + 0.5) / block_;
        y[k] = (1 - w) * y_old[k] + w * y[k];
      }
    }
    std::vector<double>& t = impl_->tails[o];
    for (int k = 0; k < block_; ++k) out[o][k] += static_cast<float>(y[k] + (k < tail ? t[k] : 0.0));
    for (int k = 0; k < tail; ++k) t[k] = (k + block_ < tail ? t[k + block_] : 0.0) + y[block_ + k];
  }
  impl_->crossfade = false;
  ringing_ = tail / block_ + 2;
}

void MultiConvolver::ProcessSilence(const std::vector<float*>& out) {
  if (ringing_ <= 0) return;
  const int tail = impl_->nfft - block_;
  for (int o = 0; o < outputs_; ++o) {
    std::vector<double>& t = impl_->tails[o];
    for (int k = 0; k < block_ && k < tail; ++k) out[o][k] += static_cast<float>(t[k]);
    for (int k = 0; k < tail; ++k) t[k] = k + block_ < tail ? t[k + block_] : 0.0;
  }
  impl_->crossfade = false;
  --ringing_;
}

}  // namespace sim
}  // namespace sarmap
