#include "sound_localisation/testing/room_simulation.h"

#include <fftw3.h>

#include <cmath>
#include <mutex>
#include <random>

#include "sim/acoustics.h"
#include "sound_localisation/stft.h"

namespace sarmap {
namespace sound {

std::vector<float> RoomImpulseResponse(const Room& room, const Eigen::Vector3d& src,
                                       const Eigen::Vector3d& mic) {
  sim::ShoeboxRoom box;
  box.max = room.size_m;
  sim::RirOptions options;
  options.sample_rate_hz = room.sample_rate_hz;
  options.speed_of_sound_mps = room.speed_of_sound_mps;
  options.max_length_s = room.max_rir_s;
  options.exact_order = 1 << 20;  // every image a windowed sinc: short responses, exact delays
  options.sinc_half_width = 16;
  options.reverb = room.rt60_s > 0;
  if (options.reverb) {
    const double alpha = sim::SabineAbsorptionForRt60(box.Volume(), box.Surface(), room.rt60_s);
    box.beta.fill(std::sqrt(1 - alpha));
  }
  // ImageSourceRir gives pressure per unit pressure at 1 m (1/r); a point source of unit
  // strength radiates 1/(4 pi r).
  std::vector<float> h = sim::ImageSourceRir(box, src, mic, options);
  h.resize(static_cast<size_t>(room.max_rir_s * room.sample_rate_hz), 0.0f);
  for (float& v : h) v = static_cast<float>(v / (4 * M_PI));
  return h;
}

std::vector<float> Convolve(const std::vector<float>& x, const std::vector<float>& h) {
  int n = 1;
  while (n < static_cast<int>(x.size() + h.size())) n *= 2;
  Fft fft(n);
  std::vector<float> a(n, 0.0f), b(n, 0.0f), y(n);
  std::copy(x.begin(), x.end(), a.begin());
  std::copy(h.begin(), h.end(), b.begin());
  std::vector<ComplexF> A(n / 2 + 1), B(n / 2 + 1);
  fft.Forward(a.data(), A.data());
  fft.Forward(b.data(), B.data());
  for (size_t k = 0; k < A.size(); ++k) A[k] *= B[k];
  fft.Inverse(A.data(), y.data());
  y.resize(x.size());
  return y;
}

std::vector<std::vector<float>> SimulateRoom(const Room& room, const Eigen::Matrix3Xd& mics,
                                             const std::vector<SimSource>& sources,
                                             size_t num_samples, double noise_std, uint32_t seed) {
  const int m = static_cast<int>(mics.cols());
  std::vector<std::vector<float>> out(m, std::vector<float>(num_samples, 0.0f));
  for (const SimSource& s : sources) {
    std::vector<float> sig(num_samples, 0.0f);
    for (size_t i = 0; i < num_samples && i < s.signal.size(); ++i)
      sig[i] = static_cast<float>(s.signal[i] * s.gain);
    for (int c = 0; c < m; ++c) {
      const auto y = Convolve(sig, RoomImpulseResponse(room, s.position_m, mics.col(c)));
      for (size_t i = 0; i < num_samples; ++i) out[c][i] += y[i];
    }
  }
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(noise_std));
  if (noise_std > 0)
    for (auto& ch : out)
      for (float& v : ch) v += noise(rng);
  return out;
}

namespace {

// Band-limited value of x at fractional sample p (Hann-windowed sinc, 2h taps).
double SincAt(const std::vector<float>& x, double p, int h) {
  const int64_t i0 = static_cast<int64_t>(std::floor(p));
  double y = 0;
  for (int64_t k = i0 - h + 1; k <= i0 + h; ++k) {
    if (k < 0 || k >= static_cast<int64_t>(x.size())) continue;
    const double d = p - static_cast<double>(k);
    const double s = std::abs(d) < 1e-12 ? 1.0 : std::sin(M_PI * d) / (M_PI * d);
    y += x[k] * s * (0.5 + 0.5 * std::cos(M_PI * d / h));
  }
  return y;
}

}  // namespace

std::vector<float> RecordAsynchronously(const std::vector<float>& sync, double tau_s, double delta,
                                        int fs, int half_taps) {
  std::vector<float> x(sync.size());
  for (size_t k = 0; k < x.size(); ++k)
    x[k] = static_cast<float>(
        SincAt(sync, (static_cast<double>(k) - tau_s * fs) / (1.0 + delta), half_taps));
  return x;
}

}  // namespace sound
}  // namespace sarmap
