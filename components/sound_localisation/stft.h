#pragma once
// Short-time Fourier transform with FFTW (single precision): a Hann-windowed analysis of
// fft_size samples every hop_size samples, and the matching weighted overlap-add synthesis.

#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace sarmap {
namespace sound {

using ComplexF = std::complex<float>;

class Fft {
 public:
  explicit Fft(int size);
  ~Fft();
  Fft(const Fft&) = delete;
  Fft& operator=(const Fft&) = delete;
  int size() const { return size_; }
  int num_bins() const { return size_ / 2 + 1; }
  // Real -> half spectrum (num_bins), unnormalised.
  void Forward(const float* in, ComplexF* out);
  // Half spectrum -> real, scaled by 1/size (so Inverse(Forward(x)) == x).
  void Inverse(const ComplexF* in, float* out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int size_;
};

// Turns a stream of multichannel samples into frames of spectra.
class MultichannelStft {
 public:
  MultichannelStft(int num_channels, int fft_size, int hop_size);
  int num_channels() const { return num_channels_; }
  int fft_size() const { return fft_size_; }
  int hop_size() const { return hop_size_; }
  int num_bins() const { return fft_size_ / 2 + 1; }
  // Adds `frames` samples of each selected channel from an interleaved int16 block with
  // `block_channels` channels; channel_map[i] is the block channel of output channel i.
  // Calls on_frame(spectra, end_sample) for every complete analysis frame; spectra is
  // num_bins x num_channels; end_sample is the stream index one past the frame's last sample.
  template <class F>
  void PushInterleaved(const int16_t* data, int frames, int block_channels,
                       const std::vector<int>& channel_map, F&& on_frame) {
    for (int i = 0; i < frames; ++i) {
      for (int c = 0; c < num_channels_; ++c)
        ring_[c][fill_] = data[i * block_channels + channel_map[c]] * (1.0f / 32768.0f);
      SampleAdded(on_frame);
    }
  }
  // Same for channel-major float input (channels[c][i]).
  template <class F>
  void PushFloat(const std::vector<std::vector<float>>& channels, size_t begin, size_t count, F&& on_frame) {
    for (size_t i = begin; i < begin + count; ++i) {
      for (int c = 0; c < num_channels_; ++c) ring_[c][fill_] = channels[c][i];
      SampleAdded(on_frame);
    }
  }
  void Reset();
  const std::vector<float>& window() const { return window_; }

 private:
  // After one sample of every channel went into the ring at fill_: on a full frame, analyses
  // it, hands it to on_frame and keeps the overlap for the next.
  template <class F>
  void SampleAdded(F& on_frame) {
    ++fill_;
    ++samples_seen_;
    if (fill_ == fft_size_) {
      Analyse();
      on_frame(spectra_, samples_seen_);
      for (int c = 0; c < num_channels_; ++c)
        std::copy(ring_[c].begin() + hop_size_, ring_[c].end(), ring_[c].begin());
      fill_ = fft_size_ - hop_size_;
    }
  }
  void Analyse();
  int num_channels_, fft_size_, hop_size_;
  int fill_ = 0;
  int64_t samples_seen_ = 0;
  std::vector<float> window_;
  std::vector<std::vector<float>> ring_;
  std::vector<float> scratch_;
  Eigen::MatrixXcf spectra_;
  Fft fft_;
};

// Weighted overlap-add resynthesis of a mono stream from spectra made by MultichannelStft
// (Hann analysis window, hop <= fft/2): output hop_size samples per frame.
class OverlapAdd {
 public:
  OverlapAdd(int fft_size, int hop_size);
  // Returns the hop_size samples completed by this frame.
  const std::vector<float>& Push(const ComplexF* spectrum);

 private:
  int fft_size_, hop_size_;
  std::vector<float> window_, accumulator_, frame_, out_;
  float norm_ = 1;
  Fft fft_;
};

}  // namespace sound
}  // namespace sarmap
