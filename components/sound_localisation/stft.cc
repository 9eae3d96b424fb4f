#include "sound_localisation/stft.h"

#include <fftw3.h>

#include <cmath>
#include <mutex>
#include <stdexcept>

namespace sarmap {
namespace sound {

namespace {
std::mutex& PlannerMutex() {  // FFTW's planner is not thread-safe
  static std::mutex m;
  return m;
}
std::vector<float> Hann(int n) {
  std::vector<float> w(n);
  for (int i = 0; i < n; ++i) w[i] = 0.5f - 0.5f * std::cos(2 * M_PI * i / n);  // periodic
  return w;
}
}  // namespace

struct Fft::Impl {
  float* real = nullptr;
  fftwf_complex* spec = nullptr;
  fftwf_plan forward = nullptr, inverse = nullptr;
};

Fft::Fft(int size) : impl_(new Impl), size_(size) {
  if (size < 8 || size % 2) throw std::invalid_argument("FFT size must be even and >= 8");
  std::lock_guard<std::mutex> lock(PlannerMutex());
  impl_->real = fftwf_alloc_real(size);
  impl_->spec = fftwf_alloc_complex(size / 2 + 1);
  impl_->forward = fftwf_plan_dft_r2c_1d(size, impl_->real, impl_->spec, FFTW_ESTIMATE);
  impl_->inverse = fftwf_plan_dft_c2r_1d(size, impl_->spec, impl_->real, FFTW_ESTIMATE);
}

Fft::~Fft() {
  std::lock_guard<std::mutex> lock(PlannerMutex());
  fftwf_destroy_plan(impl_->forward);
  fftwf_destroy_plan(impl_->inverse);
  fftwf_free(impl_->real);
  fftwf_free(impl_->spec);
}

void Fft::Forward(const float* in, ComplexF* out) {
  std::copy(in, in + size_, impl_->real);
  fftwf_execute(impl_->forward);
  const auto* s = reinterpret_cast<const ComplexF*>(impl_->spec);
  std::copy(s, s + num_bins(), out);
}

void Fft::Inverse(const ComplexF* in, float* out) {
  auto* s = reinterpret_cast<ComplexF*>(impl_->spec);
  std::copy(in, in + num_bins(), s);
  fftwf_execute(impl_->inverse);
  const float scale = 1.0f / size_;
  for (int i = 0; i < size_; ++i) out[i] = impl_->real[i] * scale;
}

MultichannelStft::MultichannelStft(int num_channels, int fft_size, int hop_size)
    : num_channels_(num_channels), fft_size_(fft_size), hop_size_(hop_size), window_(Hann(fft_size)),
      ring_(num_channels, std::vector<float>(fft_size, 0.0f)), scratch_(fft_size),
      spectra_(fft_size / 2 + 1, num_channels), fft_(fft_size) {
  if (num_channels < 1) throw std::invalid_argument("STFT needs at least one channel");
  if (hop_size < 1 || hop_size > fft_size) throw std::invalid_argument("STFT hop must be in [1, fft_size]");
}

void MultichannelStft::Reset() {
  fill_ = 0;
  samples_seen_ = 0;
}

void MultichannelStft::Analyse() {
  for (int c = 0; c < num_channels_; ++c) {
    for (int i = 0; i < fft_size_; ++i) scratch_[i] = ring_[c][i] * window_[i];
    fft_.Forward(scratch_.data(), spectra_.col(c).data());
  }
}

OverlapAdd::OverlapAdd(int fft_size, int hop_size)
    : fft_size_(fft_size), hop_size_(hop_size), window_(Hann(fft_size)), accumulator_(fft_size, 0.0f),
      frame_(fft_size), out_(hop_size), fft_(fft_size) {
  // Hann analysis, no synthesis window: sum of shifted Hann windows is fft/(2 hop) for hop | fft/2.
  double sum = 0;
  for (int i = 0; i < fft_size; i += hop_size) sum += window_[i];
  norm_ = static_cast<float>(1.0 / std::max(sum, 1e-9));
}

const std::vector<float>& OverlapAdd::Push(const ComplexF* spectrum) {
  fft_.Inverse(spectrum, frame_.data());
  for (int i = 0; i < fft_size_; ++i) accumulator_[i] += frame_[i] * norm_;
  std::copy(accumulator_.begin(), accumulator_.begin() + hop_size_, out_.begin());
  std::copy(accumulator_.begin() + hop_size_, accumulator_.end(), accumulator_.begin());
  std::fill(accumulator_.end() - hop_size_, accumulator_.end(), 0.0f);
  return out_;
}

}  // namespace sound
}  // namespace sarmap
