#include "speech/enhancer.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace sarmap {
namespace speech {
namespace {
// The fluctuation threshold needs this many level changes below the threshold first (0.26 s
// of 16 ms frames).
constexpr int kMinChangeFrames = 16;
}  // namespace

using ComplexD = std::complex<double>;

MultiBeamEnhancer::MultiBeamEnhancer(sound::ArrayGeometry geometry, EnhancerOptions options)
    : geometry_(std::move(geometry)), options_(std::move(options)),
      stft_(geometry_.num_mics(), options_.fft_size, options_.hop_size),
      noise_(options_.fft_size / 2 + 1, Eigen::MatrixXcd::Zero(geometry_.num_mics(), geometry_.num_mics())),
      out_spec_(options_.fft_size / 2 + 1) {}

void MultiBeamEnhancer::Push(const int16_t* data, int frames, int block_channels, const std::vector<Beam>& beams,
                             std::map<int64_t, std::vector<float>>* out) {
  for (auto it = beams_.begin(); it != beams_.end();) {
    bool wanted = false;
    for (const Beam& b : beams) wanted |= b.id == it->first;
    it = wanted ? std::next(it) : beams_.erase(it);
  }
  stft_.PushInterleaved(data, frames, block_channels, geometry_.channel_map,
                        [&](const Eigen::MatrixXcf& X, int64_t end_sample) { OnFrame(X, end_sample, beams, out); });
}

void MultiBeamEnhancer::ComputeWeights(BeamState* s) {
  const int m = geometry_.num_mics();
  const int nb = options_.fft_size / 2 + 1;
  const Eigen::VectorXd tau = geometry_.Delays(s->direction);
  const double dw = 2 * M_PI * geometry_.sample_rate_hz / options_.fft_size;
  s->weights.resize(nb, m);
  s->noise_psd.assign(nb, 0.0);
  const bool mvdr = using_mvdr();
  Eigen::VectorXcd d(m), w(m);
  for (int k = 0; k < nb; ++k) {
    for (int i = 0; i < m; ++i) d(i) = std::polar(1.0, -dw * k * tau(i));
    const Eigen::MatrixXcd& phi = noise_[k];
    if (mvdr && k > 0 && k < nb - 1) {
      const double load = std::max(1e-12, options_.diagonal_loading * phi.trace().real() / m);
      const Eigen::MatrixXcd loaded = phi + load * Eigen::MatrixXcd::Identity(m, m);
      Eigen::LDLT<Eigen::MatrixXcd> ldlt(loaded);
      const Eigen::VectorXcd pd = ldlt.solve(d);
      const ComplexD den = d.dot(pd);  // d^H Phi^-1 d
      if (ldlt.info() == Eigen::Success && std::abs(den) > 1e-20 && pd.allFinite()) w = pd / den;
      else w = d / static_cast<double>(m);
    } else {
      w = d / static_cast<double>(m);
    }
    s->weights.row(k) = w.transpose();
    s->noise_psd[k] = std::max(0.0, w.dot(phi * w).real());  // w^H Phi_n w
  }
  s->frames_since_weights = 0;
}

int64_t MultiBeamEnhancer::FirstOutputIndex(int64_t id) const {
  const auto it = beams_.find(id);
  return it == beams_.end() ? -1 : it->second.first_output_index;
}

void MultiBeamEnhancer::OnFrame(const Eigen::MatrixXcf& X, int64_t end_sample, const std::vector<Beam>& beams,
                                std::map<int64_t, std::vector<float>>* out) {
  const int m = geometry_.num_mics();
  const int nb = options_.fft_size / 2 + 1;
  const double hop_s = static_cast<double>(options_.hop_size) / geometry_.sample_rate_hz;
  const double energy = X.squaredNorm();
  if (noise_floor_ < 0) noise_floor_ = energy;
  const bool noise = energy < noise_floor_ * std::pow(10.0, options_.activity_snr_db / 10);
  if (energy < noise_floor_) noise_floor_ = energy;
  else noise_floor_ *= std::pow(10.0, options_.noise_rise_db_per_s * hop_s / 10);
  noise_floor_ = std::max(noise_floor_, 1e-20);
  if (noise) {
    const double a = std::max(hop_s / options_.noise_average_s, 1.0 / (noise_frames_ + 1));
    Eigen::VectorXcd x(m);
    for (int k = 0; k < nb; ++k) {
      for (int i = 0; i < m; ++i) x(i) = ComplexD(X(k, i).real(), X(k, i).imag());
      noise_[k] = (1 - a) * noise_[k] + a * (x * x.adjoint());
    }
    ++noise_frames_;
  }
  const double gmin = std::pow(10.0, options_.post_filter_floor_db / 20);
  for (const Beam& b : beams) {
    BeamState& s = beams_[b.id];
    if (!s.ola) {
      s.ola = std::make_unique<sound::OverlapAdd>(options_.fft_size, options_.hop_size);
      s.prev_clean.assign(nb, 0.0);
      s.direction = b.direction;
      // Every frame adds hop_size samples to each beam; frame 0 ends at sample fft_size.
      s.first_output_index = end_sample - options_.fft_size;
    }
    if (s.direction.dot(b.direction) < std::cos(2.0 * M_PI / 180) || s.frames_since_weights > 16) {
      s.direction = b.direction;
      ComputeWeights(&s);
    }
    ++s.frames_since_weights;
    for (int k = 0; k < nb; ++k) {
      ComplexD y = 0;
      for (int i = 0; i < m; ++i) y += std::conj(s.weights(k, i)) * ComplexD(X(k, i).real(), X(k, i).imag());
      double g = 1.0;
      if (options_.post_filter && s.noise_psd[k] > 0) {
        const double p = std::norm(y);
        const double lambda = s.noise_psd[k];
        const double gamma = p / lambda;
        const double a = options_.decision_directed_alpha;
        const double xi = a * s.prev_clean[k] / lambda + (1 - a) * std::max(gamma - 1, 0.0);
        g = std::max(xi / (1 + xi), gmin);
        s.prev_clean[k] = g * g * p;
      }
      out_spec_[k] = sound::ComplexF(static_cast<float>(g * y.real()), static_cast<float>(g * y.imag()));
    }
    const auto& samples = s.ola->Push(out_spec_.data());
    auto& dst = (*out)[b.id];
    dst.insert(dst.end(), samples.begin(), samples.end());
  }
}

// ---------------------------------------------------------------- VAD

VoiceActivityDetector::VoiceActivityDetector(int rate, VadOptions options)
    : rate_(rate),
      options_(options),
      frame_len_(std::max(1, static_cast<int>(options.frame_s * rate))),
      change_decay_(std::exp(-options.frame_s / options.fluctuation_time_s)) {}

void VoiceActivityDetector::Push(const float* x, size_t count, std::vector<Utterance>* done) {
  for (size_t i = 0; i < count; ++i) {
    const float v = std::clamp(x[i] * 32768.0f, -32768.0f, 32767.0f);
    history_.push_back(static_cast<int16_t>(std::lrint(v)));
    frame_.push_back(x[i]);
    ++position_;
    if (static_cast<int>(frame_.size()) < frame_len_) continue;
    double e = 0;
    for (float s : frame_) e += static_cast<double>(s) * s;
    frame_.clear();
    const double db = 10 * std::log10(e / frame_len_ + 1e-14);
    // Digital silence (exact zeros: a beam's first overlap-add samples, zeros filling a dropout
    // of an asynchronous card) says nothing about the room's noise: it neither sets nor lowers the
    // floor. Otherwise the floor fell to -140 dB and, at its slow rise (2 dB/s), the VAD read
    // everything after it as speech for about a minute.
    const bool digital_silence = db < -120.0;
    if (!floor_init_ && !digital_silence) {
      floor_ = db;
      previous_db_ = db;
      floor_init_ = true;
    }
    double threshold_db = options_.threshold_db;
    if (change_frames_ >= kMinChangeFrames)
      threshold_db = std::max(threshold_db, options_.fluctuation_factor * change_sum_db_ / change_weight_);
    const bool loud = floor_init_ && !digital_silence && db > floor_ + threshold_db;
    if (floor_init_ && !digital_silence) {
      if (!loud && !previous_loud_ && options_.fluctuation_factor > 0) {
        // Exponentially weighted mean of |level change| between two frames that are both below
        // the threshold, normalised by its weight so that the first frames give their plain mean.
        // Speech, which changes as fast, does not enter it (its loud frames are left out); the
        // noise's own quiet frames do, even inside an utterance that the noise opened, so a VAD
        // started on the residual does not wait for an end that never comes.
        change_sum_db_ = change_decay_ * change_sum_db_ + std::abs(db - previous_db_);
        change_weight_ = change_decay_ * change_weight_ + 1;
        ++change_frames_;
      }
      previous_db_ = db;
      previous_loud_ = loud;
      if (db < floor_) floor_ = db;
      else floor_ += options_.floor_rise_db_per_s * options_.frame_s;
    }
    if (!in_speech_ && loud) {
      in_speech_ = true;
      speech_start_ = position_ - frame_len_;
      last_loud_ = position_;
    } else if (in_speech_) {
      if (loud) last_loud_ = position_;
      if (position_ - last_loud_ > options_.hangover_s * rate_ ||
          position_ - speech_start_ > options_.max_utterance_s * rate_)
        Close(done);
    }
    if (!in_speech_) {
      // Keep only the pre-roll.
      const int64_t keep = static_cast<int64_t>(options_.pre_roll_s * rate_);
      if (static_cast<int64_t>(history_.size()) > 2 * keep + frame_len_) {
        const int64_t drop = static_cast<int64_t>(history_.size()) - keep;
        history_.erase(history_.begin(), history_.begin() + drop);
        history_start_ += drop;
      }
    }
  }
}

void VoiceActivityDetector::Close(std::vector<Utterance>* done) {
  in_speech_ = false;
  if (last_loud_ - speech_start_ < options_.min_speech_s * rate_) return;
  Utterance u;
  u.start_sample = speech_start_;
  u.end_sample = std::min(position_, last_loud_ + static_cast<int64_t>(options_.hangover_s * rate_));
  u.samples_start = std::max(history_start_, speech_start_ - static_cast<int64_t>(options_.pre_roll_s * rate_));
  u.samples.assign(history_.begin() + (u.samples_start - history_start_), history_.begin() + (u.end_sample - history_start_));
  done->push_back(std::move(u));
}

void VoiceActivityDetector::Flush(std::vector<Utterance>* done) {
  if (in_speech_) Close(done);
}

std::vector<float> Resample(const std::vector<float>& x, int from_hz, int to_hz) {
  if (from_hz == to_hz) return x;
  const double ratio = static_cast<double>(to_hz) / from_hz;
  const double cutoff = 0.45 * std::min(1.0, ratio);  // of the input rate
  const int half = 24;
  const size_t n_out = static_cast<size_t>(std::floor(x.size() * ratio));
  std::vector<float> y(n_out);
  for (size_t n = 0; n < n_out; ++n) {
    const double t = n / ratio;  // input sample position
    const int c = static_cast<int>(std::floor(t));
    double acc = 0;
    for (int k = c - half + 1; k <= c + half; ++k) {
      if (k < 0 || k >= static_cast<int>(x.size())) continue;
      const double d = t - k;
      const double arg = 2 * cutoff * d;
      const double sinc = std::abs(arg) < 1e-9 ? 1.0 : std::sin(M_PI * arg) / (M_PI * arg);
      const double w = 0.5 + 0.5 * std::cos(M_PI * d / half);
      acc += x[k] * 2 * cutoff * sinc * w;
    }
    y[n] = static_cast<float>(acc);
  }
  return y;
}

}  // namespace speech
}  // namespace sarmap
