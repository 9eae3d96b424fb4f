#include "mic_calibrate/tdoa_extraction.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <stdexcept>

#include <fftw3.h>
#include <sndfile.h>

namespace sarmap {
namespace mic_calibrate {
namespace {

// FFT cross-correlation of a reference snippet against a longer search window.
class Correlator {
 public:
  explicit Correlator(int n) : n_(n) {
    a_ = fftw_alloc_real(n);
    b_ = fftw_alloc_real(n);
    fa_ = fftw_alloc_complex(n / 2 + 1);
    fb_ = fftw_alloc_complex(n / 2 + 1);
    pa_ = fftw_plan_dft_r2c_1d(n, a_, fa_, FFTW_ESTIMATE);
    pb_ = fftw_plan_dft_r2c_1d(n, b_, fb_, FFTW_ESTIMATE);
    pinv_ = fftw_plan_dft_c2r_1d(n, fa_, a_, FFTW_ESTIMATE);
  }
  ~Correlator() {
    fftw_destroy_plan(pa_);
    fftw_destroy_plan(pb_);
    fftw_destroy_plan(pinv_);
    fftw_free(a_);
    fftw_free(b_);
    fftw_free(fa_);
    fftw_free(fb_);
  }
  Correlator(const Correlator&) = delete;
  Correlator& operator=(const Correlator&) = delete;

  // c[l] = sum_i ref[i] * win[i + l], l = 0 .. win.size() - ref.size(); PHAT-weighted if asked.
  std::vector<double> Correlate(const std::vector<double>& ref, const std::vector<double>& win,
                                bool phat) {
    std::fill(a_, a_ + n_, 0.0);
    std::fill(b_, b_ + n_, 0.0);
    std::copy(ref.begin(), ref.end(), a_);
    std::copy(win.begin(), win.end(), b_);
    fftw_execute(pa_);
    fftw_execute(pb_);
    for (int i = 0; i < n_ / 2 + 1; ++i) {
      const std::complex<double> x(fa_[i][0], fa_[i][1]), y(fb_[i][0], fb_[i][1]);
      std::complex<double> r = std::conj(x) * y;
      if (phat) r /= std::max(std::abs(r), 1e-20);
      fa_[i][0] = r.real();
      fa_[i][1] = r.imag();
    }
    fftw_execute(pinv_);
    const int lags = static_cast<int>(win.size() - ref.size()) + 1;
    return std::vector<double>(a_, a_ + lags);
  }

 private:
  int n_;
  double *a_, *b_;
  fftw_complex *fa_, *fb_;
  fftw_plan pa_, pb_, pinv_;
};

struct Biquad {
  double b0, b1, b2, a1, a2, z1 = 0, z2 = 0;
  float Step(float x) {
    const double y = b0 * x + z1;
    z1 = b1 * x - a1 * y + z2;
    z2 = b2 * x - a2 * y;
    return static_cast<float>(y);
  }
};

// RBJ high-pass biquad with quality q.
Biquad HighPassBiquad(double fs, double fc, double q) {
  const double w0 = 2 * M_PI * fc / fs, alpha = std::sin(w0) / (2 * q), cw = std::cos(w0);
  const double a0 = 1 + alpha;
  Biquad b;
  b.b0 = (1 + cw) / 2 / a0;
  b.b1 = -(1 + cw) / a0;
  b.b2 = (1 + cw) / 2 / a0;
  b.a1 = -2 * cw / a0;
  b.a2 = (1 - alpha) / a0;
  return b;
}

}  // namespace

void HighPass(std::vector<float>* x, double fs, double fc) {
  if (fc <= 0) return;
  // 4th-order Butterworth: two biquads with q = 0.5412 and 1.3066.
  Biquad s1 = HighPassBiquad(fs, fc, 0.54119610), s2 = HighPassBiquad(fs, fc, 1.30656296);
  for (float& v : *x) v = s2.Step(s1.Step(v));
}

TdoaData ExtractTdoas(const Recording& rec, const ExtractionOptions& o, ExtractionStats* stats) {
  common::ValidateOptions(o);
  const int N = static_cast<int>(rec.channels.size());
  if (N < 2) throw std::invalid_argument("the recording has " + std::to_string(N) + " channel(s); need >= 2");
  if (!(rec.sample_rate_hz > 0)) throw std::invalid_argument("sample rate must be > 0");
  const double fs = rec.sample_rate_hz;
  std::vector<std::vector<float>> x = rec.channels;
  for (auto& c : x) HighPass(&c, fs, o.highpass_hz);
  std::vector<double> start(N, 0.0);
  if (!rec.channel_start_s.empty()) start = rec.channel_start_s;

  // Onsets on the reference channel: frame energy crossing floor + threshold.
  const std::vector<float>& ref = x[0];
  const int frame = std::max(1, static_cast<int>(std::lround(o.frame_s * fs)));
  const int num_frames = static_cast<int>(ref.size()) / frame;
  std::vector<double> energy(num_frames);
  for (int f = 0; f < num_frames; ++f) {
    double e = 0;
    for (int i = 0; i < frame; ++i) e += double(ref[f * frame + i]) * ref[f * frame + i];
    energy[f] = e / frame + 1e-20;
  }
  if (num_frames < 10) throw std::invalid_argument("recording too short");
  std::vector<double> sorted = energy;
  std::nth_element(sorted.begin(), sorted.begin() + num_frames / 5, sorted.end());
  const double floor = sorted[num_frames / 5];
  const double thr = floor * std::pow(10.0, o.onset_threshold_db / 10);
  std::vector<long> onsets;
  const long spacing = std::lround(o.min_event_spacing_s * fs);
  for (int f = 1; f < num_frames; ++f) {
    if (energy[f] > thr && energy[f - 1] <= thr) {
      const long s = static_cast<long>(f) * frame;
      if (onsets.empty() || s - onsets.back() >= spacing) onsets.push_back(s);
    }
  }

  const long L = std::lround(o.max_lag_s * fs);
  const long W = std::lround(o.window_s * fs);
  const long pre = std::lround(o.pre_onset_s * fs);
  int nfft = 1;
  while (nfft < 2 * L + 2 * W) nfft *= 2;
  Correlator corr(nfft);
  const bool phat = o.method == "gcc_phat";

  TdoaData data;
  data.num_mics = N;
  std::vector<std::vector<double>> rows;
  ExtractionStats local;
  for (long onset : onsets) {
    const long r0 = onset - pre;
    if (r0 < 0 || r0 + W > static_cast<long>(ref.size())) continue;
    std::vector<double> r(ref.begin() + r0, ref.begin() + r0 + W);
    std::vector<double> row(N - 1, std::nan(""));
    for (int n = 1; n < N; ++n) {
      // Channel n's sample index at reference time (r0 / fs + start[0]).
      const double shift = (start[0] - start[n]) * fs;
      const long c0 = r0 + std::lround(shift) - L;
      const double frac_shift = std::lround(shift) - shift;  // sub-sample part of the alignment
      const std::vector<float>& y = x[n];
      std::vector<double> win(2 * L + W, 0.0);
      for (long i = 0; i < static_cast<long>(win.size()); ++i) {
        const long j = c0 + i;
        if (j >= 0 && j < static_cast<long>(y.size())) win[i] = y[j];
      }
      const std::vector<double> c = corr.Correlate(r, win, phat);
      int best = 0;
      for (int l = 1; l < static_cast<int>(c.size()); ++l)
        if (c[l] > c[best]) best = l;
      // Peak ratio against the best value away from the peak (ambiguity check).
      const int guard = std::max(2, static_cast<int>(std::lround(1e-3 * fs)));
      double second = 1e-30;
      for (int l = 0; l < static_cast<int>(c.size()); ++l)
        if (std::abs(l - best) > guard) second = std::max(second, c[l]);
      if (c[best] <= 0 || c[best] / second < o.min_peak_ratio) {
        ++local.missing;
        continue;
      }
      double delta = 0;  // parabolic sub-sample interpolation
      if (best > 0 && best + 1 < static_cast<int>(c.size())) {
        const double ym = c[best - 1], y0 = c[best], yp = c[best + 1];
        const double den = ym - 2 * y0 + yp;
        if (std::abs(den) > 1e-30) delta = std::clamp(0.5 * (ym - yp) / den, -0.5, 0.5);
      }
      const double lag = best - L + delta;  // samples of channel n after the reference
      row[n - 1] = (lag + frac_shift) / fs;
    }
    data.times_s.push_back(r0 / fs + pre / fs);
    if (rec.reference_start_utime != 0) {
      data.utimes.push_back(rec.reference_start_utime +
                            std::llround((start[0] + data.times_s.back()) * 1e6));
    }
    rows.push_back(row);
  }
  local.events = static_cast<int>(rows.size());
  data.tdoa_s.resize(static_cast<long>(rows.size()), N - 1);
  for (size_t k = 0; k < rows.size(); ++k)
    for (int n = 0; n < N - 1; ++n) data.tdoa_s(k, n) = rows[k][n];
  if (local.missing > 0) {
    local.warnings.push_back(std::to_string(local.missing) +
                             " TDOAs had a weak or ambiguous correlation peak and are missing");
  }
  if (stats) *stats = local;
  return data;
}

Recording ReadWav(const std::string& path) {
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (!f) throw std::runtime_error("cannot read audio file " + path + ": " + sf_strerror(nullptr));
  std::vector<float> buf(static_cast<size_t>(info.frames) * info.channels);
  const sf_count_t got = sf_readf_float(f, buf.data(), info.frames);
  sf_close(f);
  Recording rec;
  rec.sample_rate_hz = info.samplerate;
  rec.channels.assign(info.channels, std::vector<float>(got));
  for (sf_count_t i = 0; i < got; ++i)
    for (int c = 0; c < info.channels; ++c) rec.channels[c][i] = buf[i * info.channels + c];
  for (int c = 0; c < info.channels; ++c) rec.channel_names.push_back("ch" + std::to_string(c));
  return rec;
}

void WriteWav(const std::string& path, const Recording& rec) {
  SF_INFO info{};
  info.samplerate = static_cast<int>(std::lround(rec.sample_rate_hz));
  info.channels = static_cast<int>(rec.channels.size());
  info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
  SNDFILE* f = sf_open(path.c_str(), SFM_WRITE, &info);
  if (!f) throw std::runtime_error("cannot write " + path + ": " + sf_strerror(nullptr));
  size_t frames = 0;
  for (const auto& c : rec.channels) frames = std::max(frames, c.size());
  std::vector<float> buf(frames * info.channels, 0.0f);
  for (int c = 0; c < info.channels; ++c)
    for (size_t i = 0; i < rec.channels[c].size(); ++i) buf[i * info.channels + c] = rec.channels[c][i];
  sf_writef_float(f, buf.data(), frames);
  sf_close(f);
}

Recording SynthesiseChirps(const std::vector<Eigen::Vector3d>& mics,
                           const std::vector<double>& tau, const std::vector<double>& delta,
                           const std::vector<Eigen::Vector3d>& sources,
                           const std::vector<double>& times, const ChirpSynthesis& sy,
                           uint64_t seed) {
  const int N = static_cast<int>(mics.size());
  const double fs = sy.sample_rate_hz;
  const double t_end = (times.empty() ? 0 : times.back()) + sy.tail_s;
  double max_tau = 0;
  for (double t : tau) max_tau = std::max(max_tau, std::abs(t));
  const size_t len = static_cast<size_t>((t_end + max_tau + 0.1) * fs);
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sy.noise_rms));
  Recording rec;
  rec.sample_rate_hz = fs;
  rec.channels.assign(N, std::vector<float>(len));
  const double rate = (sy.f1_hz - sy.f0_hz) / sy.chirp_s;
  for (int n = 0; n < N; ++n) {
    auto& ch = rec.channels[n];
    for (auto& v : ch) v = noise(rng);
    rec.channel_names.push_back("mic" + std::to_string(n + 1));
    for (size_t k = 0; k < sources.size(); ++k) {
      const double d = (mics[n] - sources[k]).norm();
      const double arrival = times[k] + d / sy.speed_of_sound_mps;  // true time
      const double gain = 1.0 / std::max(d, 0.1);
      // Local clock reading u = t (1 + delta) + tau; sample i is at u = i / fs.
      const double u0 = arrival * (1 + delta[n]) + tau[n];
      const long i0 = static_cast<long>(std::floor(u0 * fs)) - 1;
      const long i1 = i0 + static_cast<long>(sy.chirp_s * fs * (1 + delta[n])) + 3;
      for (long i = std::max(0L, i0); i <= i1 && i < static_cast<long>(len); ++i) {
        const double t_true = (i / fs - tau[n]) / (1 + delta[n]);
        const double s = t_true - arrival;
        if (s < 0 || s > sy.chirp_s) continue;
        const double w = 0.5 - 0.5 * std::cos(2 * M_PI * s / sy.chirp_s);
        ch[i] += static_cast<float>(gain * w *
                                    std::sin(2 * M_PI * (sy.f0_hz * s + 0.5 * rate * s * s)));
      }
    }
  }
  return rec;
}

}  // namespace mic_calibrate
}  // namespace sarmap
