#include "sound_localisation/async_alignment.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sarmap {
namespace sound {

AsyncStreamAligner::AsyncStreamAligner(int sample_rate_hz, std::vector<double> start_offsets_s,
                                       std::vector<double> clock_drift, int num_mics, int half_width)
    : mics_(num_mics), half_width_(half_width) {
  if (num_mics < 1) throw std::invalid_argument("AsyncStreamAligner: needs at least one microphone");
  if (half_width < 1) throw std::invalid_argument("AsyncStreamAligner: half_width must be >= 1");
  if (!start_offsets_s.empty() && static_cast<int>(start_offsets_s.size()) != num_mics)
    throw std::invalid_argument("start_offsets_s has " + std::to_string(start_offsets_s.size()) +
                                " values for " + std::to_string(num_mics) + " microphones");
  if (!clock_drift.empty() && static_cast<int>(clock_drift.size()) != num_mics)
    throw std::invalid_argument("clock_drift has " + std::to_string(clock_drift.size()) + " values for " +
                                std::to_string(num_mics) + " microphones");
  for (int m = 0; m < num_mics; ++m) {
    mics_[m].offset_samples = start_offsets_s.empty() ? 0.0 : start_offsets_s[m] * sample_rate_hz;
    mics_[m].rate = 1.0 + (clock_drift.empty() ? 0.0 : clock_drift[m]);
    if (!(mics_[m].rate > 0.5 && mics_[m].rate < 2.0))
      throw std::invalid_argument("clock_drift of microphone " + std::to_string(m) + " is implausible");
  }
}

void AsyncStreamAligner::Push(int mic, int64_t first_sample, const float* data, size_t count) {
  if (mic < 0 || mic >= num_mics()) throw std::out_of_range("AsyncStreamAligner: no microphone " + std::to_string(mic));
  Mic& m = mics_[mic];
  if (!m.started) {
    m.base = first_sample;
    m.started = true;
  }
  const int64_t end = m.base + static_cast<int64_t>(m.buffer.size());
  size_t skip = 0;
  if (first_sample > end) {  // dropout: the counter jumped
    dropped_ += first_sample - end;
    m.buffer.insert(m.buffer.end(), static_cast<size_t>(first_sample - end), 0.0f);
  } else if (first_sample < end) {
    skip = static_cast<size_t>(std::min<int64_t>(end - first_sample, static_cast<int64_t>(count)));
  }
  m.buffer.insert(m.buffer.end(), data + skip, data + count);
}

// x(p) = sum_k x[k] sinc(p - k) w(p - k) over the 2H samples around p, w a Blackman window of
// half width H.
float AsyncStreamAligner::Interpolate(const Mic& m, double p) const {
  const int64_t i0 = static_cast<int64_t>(std::floor(p));
  const double frac = p - static_cast<double>(i0);
  const int h = half_width_;
  double y = 0;
  for (int k = -h + 1; k <= h; ++k) {
    const int64_t idx = i0 + k - m.base;
    if (idx < 0 || idx >= static_cast<int64_t>(m.buffer.size())) continue;
    const double d = frac - k;  // p - (i0 + k)
    const double sinc = std::abs(d) < 1e-9 ? 1.0 : std::sin(M_PI * d) / (M_PI * d);
    const double w = 0.42 + 0.5 * std::cos(M_PI * d / h) + 0.08 * std::cos(2 * M_PI * d / h);
    y += m.buffer[static_cast<size_t>(idx)] * sinc * w;
  }
  return static_cast<float>(y);
}

size_t AsyncStreamAligner::Pull(std::vector<std::vector<float>>* out) {
  out->resize(mics_.size());
  // Last reference sample every microphone can produce: all taps of p must be in the buffer.
  int64_t last = INT64_MAX;
  for (const Mic& m : mics_) {
    if (!m.started) return 0;
    const int64_t end = m.base + static_cast<int64_t>(m.buffer.size());  // one past the last sample
    // Need floor(p) + H <= end - 1, p = rate * r + offset.
    const double r_max = (static_cast<double>(end - 1 - half_width_) - m.offset_samples) / m.rate;
    last = std::min(last, static_cast<int64_t>(std::floor(r_max)));
  }
  if (last < next_) return 0;
  const size_t n = static_cast<size_t>(last - next_ + 1);
  for (size_t c = 0; c < mics_.size(); ++c) {
    Mic& m = mics_[c];
    auto& o = (*out)[c];
    o.reserve(o.size() + n);
    for (int64_t r = next_; r <= last; ++r) o.push_back(Interpolate(m, Position(m, r)));
    // Drop the samples no later output needs.
    const int64_t keep_from = static_cast<int64_t>(std::floor(Position(m, last + 1))) - half_width_;
    while (m.base < keep_from && !m.buffer.empty()) {
      m.buffer.pop_front();
      ++m.base;
    }
  }
  next_ = last + 1;
  return n;
}

}  // namespace sound
}  // namespace sarmap
