#pragma once
// Helpers for the synthetic tests (not part of the library).
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "audio_capture/audio_file.h"
#include "common/robot_config.h"
#include "sound_localisation/array_geometry.h"

namespace sarmap {
namespace sound {
namespace testing_util {

inline ArrayGeometry LoadArray(const std::string& name) {
  return ArrayGeometry::FromOptions(
      common::LoadMicArray(std::string(SARMAP_SOURCE_DIR) + "/config/arrays/" + name + ".yaml"));
}

// Real speech (CMU ARCTIC) from the shared data, normalised to unit RMS; empty if missing.
inline std::vector<float> Speech(int index) {
  static const char* files[] = {"cmu_arctic_us_aew_a0001.wav", "cmu_arctic_us_axb_a0004.wav",
                                "cmu_arctic_us_aew_a0002.wav", "cmu_arctic_us_axb_a0005.wav",
                                "arctic_a0010.wav", "cmu_arctic_us_aew_a0003.wav"};
  const std::string path = std::string(SARMAP_DATA_DIR) + "/audio/cmu_arctic/" + files[index % 6];
  if (!std::filesystem::exists(path)) return {};
  auto buf = audio::ReadAudioFile(path);
  std::vector<float> x = buf.channels[0];
  double e = 0;
  for (float v : x) e += v * v;
  const float g = static_cast<float>(1.0 / std::sqrt(e / std::max<size_t>(1, x.size()) + 1e-12));
  for (float& v : x) v *= g;
  return x;
}

// Adds gain * x delayed by delay_samples (windowed sinc) to y.
inline void AddDelayed(const std::vector<float>& x, double delay_samples, double gain,
                       std::vector<float>* y) {
  const int half = 16;
  for (int k = -half; k <= half; ++k) {
    const int n = static_cast<int>(std::floor(delay_samples)) + k;
    const double t = n - delay_samples;
    const double sinc = std::abs(t) < 1e-9 ? 1.0 : std::sin(M_PI * t) / (M_PI * t);
    const double w = 0.5 * (1 + std::cos(M_PI * t / (half + 1)));
    const float h = static_cast<float>(gain * sinc * w);
    for (size_t i = 0; i < x.size(); ++i) {
      const long j = static_cast<long>(i) + n;
      if (j >= 0 && j < static_cast<long>(y->size())) (*y)[j] += h * x[i];
    }
  }
}

inline std::vector<float> WhiteNoise(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> d(0.0f, 1.0f);
  std::vector<float> x(n);
  for (float& v : x) v = d(rng);
  return x;
}

}  // namespace testing_util
}  // namespace sound
}  // namespace sarmap
