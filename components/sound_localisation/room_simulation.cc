#include "sound_localisation/room_simulation.h"

#include <fftw3.h>

#include <cmath>
#include <mutex>
#include <random>

#include "sound_localisation/stft.h"

namespace sarmap {
namespace sound {

std::vector<float> RoomImpulseResponse(const Room& room, const Eigen::Vector3d& src, const Eigen::Vector3d& mic) {
  const double fs = room.sample_rate_hz, c = room.speed_of_sound_mps;
  const int len = static_cast<int>(room.max_rir_s * fs);
  std::vector<float> h(len, 0.0f);
  const Eigen::Vector3d L = room.size_m;
  double beta = 0;
  if (room.rt60_s > 0) {
    const double volume = L.prod();
    const double surface = 2 * (L.x() * L.y() + L.x() * L.z() + L.y() * L.z());
    const double alpha = std::min(1.0, 0.161 * volume / (surface * room.rt60_s));
    beta = std::sqrt(1 - alpha);
  }
  const double max_dist = len / fs * c;
  const int half = 16;  // sinc half-length
  auto add = [&](double dist, double amp) {
    const double t = dist / c * fs;
    const int centre = static_cast<int>(std::floor(t));
    for (int n = centre - half + 1; n <= centre + half; ++n) {
      if (n < 0 || n >= len) continue;
      const double x = n - t;
      const double sinc = std::abs(x) < 1e-9 ? 1.0 : std::sin(M_PI * x) / (M_PI * x);
      const double w = 0.5 + 0.5 * std::cos(M_PI * x / half);
      h[n] += static_cast<float>(amp * sinc * w);
    }
  };
  const int nmax = beta > 0 ? static_cast<int>(std::ceil(max_dist / L.minCoeff())) + 1 : 0;
  const double max2 = max_dist * max_dist;
  for (int i = -nmax; i <= nmax; ++i)
    for (int px = 0; px < 2; ++px) {
      const double dx = (1 - 2 * px) * src.x() + 2 * i * L.x() - mic.x();
      if (dx * dx >= max2) continue;
      const int ox = std::abs(i - px) + std::abs(i);
      for (int j = -nmax; j <= nmax; ++j)
        for (int py = 0; py < 2; ++py) {
          const double dy = (1 - 2 * py) * src.y() + 2 * j * L.y() - mic.y();
          if (dx * dx + dy * dy >= max2) continue;
          const int oy = std::abs(j - py) + std::abs(j);
          for (int k = -nmax; k <= nmax; ++k)
            for (int pz = 0; pz < 2; ++pz) {
              // Image position: (1 - 2p) s + 2 n L per axis; reflections |n - p| + |n|.
              const double dz = (1 - 2 * pz) * src.z() + 2 * k * L.z() - mic.z();
              const double d2 = dx * dx + dy * dy + dz * dz;
              if (d2 >= max2) continue;
              const int order = ox + oy + std::abs(k - pz) + std::abs(k);
              if (beta == 0 && order > 0) continue;
              const double dist = std::sqrt(d2);
              add(dist, std::pow(beta, order) / (4 * M_PI * std::max(dist, 0.05)));
            }
        }
    }
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
                                             const std::vector<SimSource>& sources, size_t num_samples,
                                             double noise_std, uint32_t seed) {
  const int m = static_cast<int>(mics.cols());
  std::vector<std::vector<float>> out(m, std::vector<float>(num_samples, 0.0f));
  for (const SimSource& s : sources) {
    std::vector<float> sig(num_samples, 0.0f);
    for (size_t i = 0; i < num_samples && i < s.signal.size(); ++i) sig[i] = static_cast<float>(s.signal[i] * s.gain);
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

std::vector<float> RecordAsynchronously(const std::vector<float>& sync, double tau_s, double delta, int fs,
                                        int half_taps) {
  std::vector<float> x(sync.size());
  for (size_t k = 0; k < x.size(); ++k)
    x[k] = static_cast<float>(SincAt(sync, (static_cast<double>(k) - tau_s * fs) / (1.0 + delta), half_taps));
  return x;
}

}  // namespace sound
}  // namespace sarmap
