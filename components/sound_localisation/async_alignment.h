#pragma once
// Alignment of an asynchronous microphone array (several sound cards, each with its own clock
// and sample counter) to one reference clock before DOA estimation.
//
// Clock model (Su 2017, eq. 3.18, as estimated by sarmap-mic-calibrate): a sound reaching
// microphone n at reference time t is recorded at that card's time
//     t_n = (1 + delta_n) t + tau_n
// (tau_n start offset, delta_n fractional clock drift, both 0 for the reference microphone).
// The synchronous signal is therefore s_n(t) = x_n((1 + delta_n) t + tau_n): for reference
// sample r the aligner reads card sample  p = (1 + delta_n) r + tau_n fs  of microphone n, a
// fractional position, with a Blackman-windowed sinc interpolator (a fractional delay that
// also resamples by the drift). Samples that do not exist (before a card's first sample, or a
// dropout in its counter) read as zeros.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace sarmap {
namespace sound {

class AsyncStreamAligner {
 public:
  // One entry per microphone; empty vectors mean all zeros. half_width: interpolator taps on
  // each side (16 keeps the error below -60 dB up to 0.8 of Nyquist).
  AsyncStreamAligner(int sample_rate_hz, std::vector<double> start_offsets_s, std::vector<double> clock_drift,
                     int num_mics, int half_width = 16);

  // Samples of microphone `mic`, the first at that card's sample counter `first_sample`.
  // A jump forward in the counter is a dropout (zeros, counted); samples already seen are skipped.
  void Push(int mic, int64_t first_sample, const float* data, size_t count);
  // Appends to out[m] every reference sample that all microphones can now produce; returns how many.
  size_t Pull(std::vector<std::vector<float>>* out);

  int64_t next_reference_sample() const { return next_; }
  int64_t dropped_samples() const { return dropped_; }
  int num_mics() const { return static_cast<int>(mics_.size()); }

 private:
  struct Mic {
    double offset_samples = 0, rate = 1;  // p = rate * r + offset_samples
    std::deque<float> buffer;
    int64_t base = 0;                      // card sample of buffer[0]
    bool started = false;
  };
  double Position(const Mic& m, int64_t r) const { return m.rate * static_cast<double>(r) + m.offset_samples; }
  float Interpolate(const Mic& m, double p) const;

  std::vector<Mic> mics_;
  int half_width_;
  int64_t next_ = 0;
  int64_t dropped_ = 0;
};

}  // namespace sound
}  // namespace sarmap
