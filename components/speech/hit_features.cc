#include "speech/hit_features.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace speech {
namespace {

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

int PhoneEditDistance(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = static_cast<int>(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

HitFeatures ComputeHitFeatures(const int16_t* x, size_t count, double onset_s, double end_s, double hit_start_s,
                               double hit_end_s, double log_ratio) {
  struct {
    double start_s, end_s, log_ratio;
  } hit{hit_start_s, hit_end_s, log_ratio};
  constexpr int kRate = 16000, kFrame = 160;
  HitFeatures f;
  f.log_ratio = hit.log_ratio;
  f.duration_s = std::max(0.01, hit.end_s - hit.start_s);
  f.ratio_per_s = hit.log_ratio / f.duration_s;
  f.utterance_s = static_cast<double>(count) / kRate;
  f.lead_s = hit.start_s - onset_s;
  f.trail_s = end_s - hit.end_s;
  // Frame energies (dB re full scale).
  std::vector<double> frame_db;
  for (size_t i = 0; i + kFrame <= count; i += kFrame) {
    double e = 0;
    for (size_t j = i; j < i + kFrame; ++j) e += static_cast<double>(x[j]) * x[j];
    frame_db.push_back(10 * std::log10(e / kFrame / (32768.0 * 32768.0) + 1e-12));
  }
  const double p95 = Percentile(frame_db, 0.95), p10 = Percentile(frame_db, 0.10);
  f.snr_db = p95 - p10;
  const size_t a = std::min(count, static_cast<size_t>(std::max(0.0, hit.start_s) * kRate));
  const size_t b = std::min(count, static_cast<size_t>(std::max(0.0, hit.end_s) * kRate));
  double hit_db = 0;
  int n = 0;
  for (size_t i = a / kFrame; i < frame_db.size() && i < b / kFrame; ++i, ++n) hit_db += frame_db[i];
  f.hit_level_db = n ? hit_db / n - p95 : -100;
  // Spectral tilt: energy of the first difference relative to the energy (white: +3 dB).
  double e0 = 0, e1 = 0;
  for (size_t i = a + 1; i < b; ++i) {
    e0 += static_cast<double>(x[i]) * x[i];
    const double d = static_cast<double>(x[i]) - x[i - 1];
    e1 += d * d;
  }
  f.tilt_db = e0 > 0 ? 10 * std::log10(e1 / e0 + 1e-12) : 0;
  // Pitch: normalised autocorrelation over 40 ms windows every 10 ms, lags 60-400 Hz.
  constexpr int kWin = 640, kMinLag = kRate / 400, kMaxLag = kRate / 60;
  std::vector<double> pitches;
  int frames = 0;
  for (size_t i = a; i < b && i + kWin + kMaxLag <= count; i += kFrame) {
    ++frames;
    double e_ref = 0;
    for (int j = 0; j < kWin; ++j) e_ref += static_cast<double>(x[i + j]) * x[i + j];
    if (e_ref <= 0) continue;
    double best = 0;
    int best_lag = 0;
    for (int lag = kMinLag; lag <= kMaxLag; ++lag) {
      double c = 0, e_lag = 0;
      for (int j = 0; j < kWin; ++j) {
        c += static_cast<double>(x[i + j]) * x[i + j + lag];
        e_lag += static_cast<double>(x[i + j + lag]) * x[i + j + lag];
      }
      const double r = c / std::sqrt(e_ref * e_lag + 1e-12);
      if (r > best) {
        best = r;
        best_lag = lag;
      }
    }
    if (best > 0.6 && best_lag > 0) pitches.push_back(static_cast<double>(kRate) / best_lag);
  }
  f.voiced_fraction = frames ? static_cast<double>(pitches.size()) / frames : 0;
  if (!pitches.empty()) {
    f.pitch_hz = Percentile(pitches, 0.5);
    f.pitch_range_st = 12 * std::log2(Percentile(pitches, 0.9) / Percentile(pitches, 0.1));
  }
  return f;
}

}  // namespace speech
}  // namespace sarmap
