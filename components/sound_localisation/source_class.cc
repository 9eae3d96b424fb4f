#include "sound_localisation/source_class.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <stdexcept>

namespace sarmap {
namespace sound {

const char* SoundClassName(SoundClass c) {
  switch (c) {
    case SoundClass::kVoice:
      return "voice";
    case SoundClass::kAlarm:
      return "alarm";
    case SoundClass::kMachinery:
      return "machinery";
    case SoundClass::kMusic:
      return "music";
    default:
      return "unknown";
  }
}

SoundClassifier::SoundClassifier(const SourceClassOptions& options, int sample_rate_hz)
    : options_(options) {
  if (sample_rate_hz <= 0)
    throw std::invalid_argument("SoundClassifier: sample rate must be positive");
  frame_rate_hz_ = static_cast<double>(sample_rate_hz) / options_.hop_size;
  const double bin_hz = static_cast<double>(sample_rate_hz) / options_.fft_size;
  const int num_bins = options_.fft_size / 2 + 1;
  bin_lo_ =
      std::clamp(static_cast<int>(std::ceil(options_.min_frequency_hz / bin_hz)), 1, num_bins - 1);
  bin_hi_ = std::clamp(static_cast<int>(std::floor(options_.max_frequency_hz / bin_hz)), bin_lo_,
                       num_bins - 1);
  history_frames_ =
      static_cast<size_t>(std::max(1.0, std::round(options_.history_s * frame_rate_hz_)));
}

void SoundClassifier::AddFrame(const std::vector<float>& power, int64_t end_sample, int present,
                               double envelope_energy) {
  if (static_cast<int>(power.size()) <= bin_hi_)
    throw std::invalid_argument("SoundClassifier::AddFrame: " + std::to_string(power.size()) +
                                " bins, need " + std::to_string(bin_hi_ + 1));
  ++frames_seen_;
  Frame f;
  f.end_sample = end_sample;
  int used = 0;
  double log_sum = 0;
  for (int k = bin_lo_; k <= bin_hi_; ++k) {
    if (power[k] < 0) continue;
    f.energy += power[k];
    log_sum += std::log(static_cast<double>(power[k]) + 1e-20);
    ++used;
  }
  // Spectral shape needs a third of the band (the peaks of a few bins are no tonality); a
  // frame with fewer bins of this source
  // still counts for the envelope.
  const int band = bin_hi_ - bin_lo_ + 1;
  std::vector<double> shape(band, -1.0);
  if (used >= std::max(8, band / 3) && f.energy > 1e-20) {
    const double mean = f.energy / used;  // f.energy: the band's energy until the envelope is set
    f.flatness = std::exp(log_sum / used) / mean;
    // Tonality: the three strongest local maxima with their neighbours.
    std::vector<std::pair<double, int>> peaks;
    auto p = [&](int k) {
      return k < bin_lo_ || k > bin_hi_ || power[k] < 0 ? 0.0 : static_cast<double>(power[k]);
    };
    for (int k = bin_lo_; k <= bin_hi_; ++k)
      if (p(k) > 0 && p(k) >= p(k - 1) && p(k) > p(k + 1)) peaks.emplace_back(p(k), k);
    std::sort(peaks.rbegin(), peaks.rend());
    double tonal = 0;
    std::vector<char> taken(band + 2, 0);
    for (size_t i = 0; i < std::min<size_t>(3, peaks.size()); ++i)
      for (int k = peaks[i].second - 1; k <= peaks[i].second + 1; ++k)
        if (!taken[k - bin_lo_ + 1]) {
          taken[k - bin_lo_ + 1] = 1;
          tonal += p(k);
        }
    f.tonality = tonal / f.energy;
    f.peak = peaks.empty() ? -1 : peaks[0].second;
    // Flux over the bins both frames hold (a directional mask changes from frame to frame).
    for (int k = bin_lo_; k <= bin_hi_; ++k) shape[k - bin_lo_] = power[k] < 0 ? -1.0 : power[k];
    if (!last_shape_.empty()) {
      double now_sum = 0, last_sum = 0;
      int common = 0;
      for (int i = 0; i < band; ++i)
        if (shape[i] >= 0 && last_shape_[i] >= 0) {
          now_sum += shape[i];
          last_sum += last_shape_[i];
          ++common;
        }
      if (common >= std::max(8, band / 3) && now_sum > 0 && last_sum > 0) {
        double d = 0;
        for (int i = 0; i < band; ++i)
          if (shape[i] >= 0 && last_shape_[i] >= 0) {
            const double diff =
                std::sqrt(shape[i] / now_sum) - std::sqrt(last_shape_[i] / last_sum);
            d += diff * diff;
          }
        f.flux = std::max(1e-9, 0.5 * d);
      }
    }
    last_shape_ = shape;
  } else {
    last_shape_.clear();
  }
  if (envelope_energy >= 0) f.energy = envelope_energy;
  // The loudest recent frame decays by ~1 dB/s so that a source that moved away still has pauses.
  max_energy_ = std::max(f.energy, max_energy_ * std::pow(10.0, -0.1 / frame_rate_hz_));
  if (present < 0)
    f.present =
        f.energy > 0 && 10 * std::log10(max_energy_ / f.energy) <= options_.present_range_db;
  else
    f.present = present > 0;
  frames_.push_back(f);
  while (frames_.size() > history_frames_) frames_.pop_front();
}

void SoundClassifier::MarkPresent(int64_t begin_sample, int64_t end_sample) {
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (it->end_sample <= begin_sample) break;
    // A pause inside a reported block (a beeper's off time) does not sound.
    if (it->end_sample <= end_sample && it->energy > 0 &&
        10 * std::log10(max_energy_ / it->energy) <= options_.present_range_db)
      it->present = true;
  }
}

SoundClassFeatures SoundClassifier::Features() const {
  SoundClassFeatures out;
  int n_present = 0, n_shape = 0, n_flux = 0;
  double level_sum = 0, level_sq = 0;
  std::map<int, int> peak_count;
  // Steadiness: of two consecutive sounding frames with a spectral shape, how often the strongest
  // peak stays in its bin.
  int steady_pairs = 0, pairs = 0, last_peak = -1;
  for (const Frame& f : frames_) {
    const int prev_peak = last_peak;
    last_peak = f.present && f.flatness >= 0 ? f.peak : -1;
    if (!f.present) continue;
    if (f.flatness >= 0 && prev_peak >= 0) {
      ++pairs;
      steady_pairs += f.peak == prev_peak;
    }
    ++n_present;
    const double level = 10 * std::log10(f.energy + 1e-20);
    level_sum += level;
    level_sq += level * level;
    if (f.flatness < 0) continue;
    ++n_shape;
    out.flatness += f.flatness;
    out.tonality += f.tonality;
    if (f.flux > 0) {
      out.flux += f.flux;
      ++n_flux;
    }
    ++peak_count[f.peak];
  }
  out.present_s = n_present / frame_rate_hz_;
  if (n_present > 1) {
    const double mean = level_sum / n_present;
    out.level_std_db = std::sqrt(std::max(0.0, level_sq / n_present - mean * mean));
  }
  if (n_shape > 0) {
    out.flatness /= n_shape;
    out.tonality /= n_shape;
    // The two commonest peak bins (+-1 bin each).
    std::vector<std::pair<int, int>> counts;
    for (const auto& [bin, c] : peak_count) {
      int near = 0;
      for (int b = bin - 1; b <= bin + 1; ++b) {
        auto it = peak_count.find(b);
        if (it != peak_count.end()) near += it->second;
      }
      counts.emplace_back(near, bin);
    }
    std::sort(counts.rbegin(), counts.rend());
    int covered = 0;
    const int first = counts[0].second;
    int second = -1000;
    for (const auto& c : counts)
      if (std::abs(c.second - first) > 2) {
        second = c.second;
        break;
      }
    for (const auto& [bin, c] : peak_count)
      if (std::abs(bin - first) <= 1 || std::abs(bin - second) <= 1) covered += c;
    out.peak_share = static_cast<double>(covered) / n_shape;
  }
  if (n_flux > 0) out.flux /= n_flux;
  out.steadiness = pairs > 0 ? static_cast<double>(steady_pairs) / pairs : 0.0;
  // Syllabic modulation: RMS of the 2-8 Hz part of the sounding stretch's normalised energy
  // envelope E(t) / mean E (DFT over the history; pauses inside it count as silence).
  size_t first = frames_.size(), last = 0;
  for (size_t i = 0; i < frames_.size(); ++i)
    if (frames_[i].present) {
      first = std::min(first, i);
      last = i;
    }
  if (first < last && last - first + 1 >= 8) {
    const size_t n = last - first + 1;
    double mean = 0;
    for (size_t i = first; i <= last; ++i) mean += frames_[i].energy;
    mean /= n;
    if (mean > 0) {
      const double df = frame_rate_hz_ / n;
      double band = 0;
      for (size_t j = 1; j <= n / 2; ++j) {
        const double hz = j * df;
        if (hz < 2.0 || hz > 8.0) continue;
        std::complex<double> acc = 0;
        for (size_t i = 0; i < n; ++i)
          acc += (frames_[first + i].energy / mean - 1.0) *
                 std::polar(1.0, -2 * M_PI * static_cast<double>(j * i) / static_cast<double>(n));
        band += 2 * std::norm(acc) / (static_cast<double>(n) * n);
      }
      out.syllabic = std::sqrt(band);
    }
  }
  return out;
}

SoundClassEstimate SoundClassifier::Decide(const SoundClassFeatures& f,
                                           const SourceClassOptions& o) {
  SoundClassEstimate e;
  e.features = f;
  if (f.present_s < std::min(o.min_present_s, o.min_voice_present_s)) return e;
  const bool long_enough = f.present_s >= o.min_present_s;
  // Each margin is the distance past its threshold, relative to the threshold, clamped to 0..1.
  auto margin = [](double value, double threshold) {
    return std::clamp(std::abs(value - threshold) / std::max(threshold, 1e-9), 0.0, 1.0);
  };
  bool early = false;  // decided before min_present_s (a voice or a clear alarm)
  const bool tonal = f.tonality >= o.tonal_min && f.flux <= o.tonal_max_flux;
  const bool sustained = f.steadiness >= o.sustained_min;
  if (tonal || sustained) {
    const bool alarm = f.peak_share >= o.alarm_peak_share;
    early = alarm && f.tonality >= o.clear_alarm_tonal_min;
    if (!long_enough && !early) return e;
    e.sound_class = alarm ? SoundClass::kAlarm : SoundClass::kMusic;
    const double held =
        tonal ? std::min(margin(f.tonality, o.tonal_min), margin(f.flux, o.tonal_max_flux))
              : margin(f.steadiness, o.sustained_min);
    e.confidence = std::min(held, margin(f.peak_share, o.alarm_peak_share));
  } else if (f.syllabic >= o.voice_syllabic_min && f.level_std_db >= o.steady_level_std_db) {
    early = true;
    e.sound_class = SoundClass::kVoice;
    e.confidence = std::min(
        {std::max(margin(f.tonality, o.tonal_min), margin(f.flux, o.tonal_max_flux)),
         margin(f.syllabic, o.voice_syllabic_min), margin(f.level_std_db, o.steady_level_std_db)});
  } else {
    if (!long_enough) return e;
    e.sound_class = SoundClass::kMachinery;
    e.confidence =
        std::min(std::max(margin(f.tonality, o.tonal_min), margin(f.flux, o.tonal_max_flux)),
                 std::max(margin(f.syllabic, o.voice_syllabic_min),
                          margin(f.level_std_db, o.steady_level_std_db)));
  }
  // Little sound heard: less sure.
  const double needed = early ? o.min_voice_present_s : o.min_present_s;
  e.confidence *= std::min(1.0, f.present_s / (2 * std::max(needed, 1e-3)));
  return e;
}

SoundClassEstimate SoundClassifier::Classify() const { return Decide(Features(), options_); }

DirectionalClassifier::DirectionalClassifier(ArrayGeometry geometry, DoaKind kind,
                                             SourceClassOptions options)
    : geometry_(std::move(geometry)),
      kind_(kind),
      options_(options),
      stft_(geometry_.num_mics(), options.fft_size, options.hop_size) {
  const double bin_hz = static_cast<double>(geometry_.sample_rate_hz) / options_.fft_size;
  const int num_bins = options_.fft_size / 2 + 1;
  bin_lo_ =
      std::clamp(static_cast<int>(std::ceil(options_.min_frequency_hz / bin_hz)), 1, num_bins - 1);
  bin_hi_ = std::clamp(static_cast<int>(std::floor(options_.max_frequency_hz / bin_hz)), bin_lo_,
                       num_bins - 1);
  power_.assign(num_bins, -1.0f);
}

void DirectionalClassifier::Push(const int16_t* data, int frames, int block_channels) {
  geometry_.CheckChannels(block_channels);
  stft_.PushInterleaved(
      data, frames, block_channels, geometry_.channel_map,
      [&](const Eigen::MatrixXcf& s, int64_t end) { OnFrame(s, stream_offset_ + end); });
  samples_seen_ += frames;
}

void DirectionalClassifier::PushFloat(const std::vector<std::vector<float>>& ch, size_t begin,
                                      size_t count) {
  stft_.PushFloat(ch, begin, count, [&](const Eigen::MatrixXcf& s, int64_t end) {
    OnFrame(s, stream_offset_ + end);
  });
  samples_seen_ += count;
}

void DirectionalClassifier::SkipSamples(int64_t samples) {
  if (samples <= 0) return;
  stream_offset_ += samples;
  samples_seen_ += samples;
}

void DirectionalClassifier::ResetStream() {
  stft_.Reset();
  stream_offset_ = samples_seen_;
}

void DirectionalClassifier::OnFrame(const Eigen::MatrixXcf& spectra, int64_t end_sample) {
  // The last replay_s of frames wait for a track that starts later: the block that first
  // reports a source holds the start of its sound (a short call may be little more).
  recent_.push_back({spectra, end_sample});
  const int64_t keep =
      static_cast<int64_t>(std::llround(options_.replay_s * geometry_.sample_rate_hz));
  while (!recent_.empty() && recent_.front().end_sample <= end_sample - keep) recent_.pop_front();
  AddFrame(spectra, end_sample, tracks_.size());
}

void DirectionalClassifier::AddFrame(const Eigen::MatrixXcf& spectra, int64_t end_sample,
                                     size_t only) {
  if (tracks_.empty()) return;
  const int m = geometry_.num_mics();
  const size_t n = tracks_.size();
  // Each bin goes to the track whose plane wave explains it best, when it does so clearly.
  std::vector<std::vector<float>> powers(n, std::vector<float>(power_.size(), -1.0f));
  coherence_.resize(n);
  std::vector<double> owned_energy(n, 0.0);
  double band_energy = 0;
  Eigen::VectorXcd x(m);
  for (int k = bin_lo_; k <= bin_hi_; ++k) {
    double norm = 0;
    for (int i = 0; i < m; ++i) {
      x(i) = std::complex<double>(spectra(k, i).real(), spectra(k, i).imag());
      norm += std::norm(x(i));
    }
    if (norm <= 1e-30) continue;
    // a^H x with a_m = exp(-j w tau_m).
    for (size_t t = 0; t < n; ++t)
      coherence_[t] =
          std::norm((tracks_[t].conj_steering.row(k - bin_lo_) * x).value()) / (m * norm);
    size_t best = 0;
    for (size_t t = 1; t < n; ++t)
      if (coherence_[t] > coherence_[best]) best = t;
    double second = 0;
    for (size_t t = 0; t < n; ++t)
      if (t != best) second = std::max(second, coherence_[t]);
    // The bin's power (mean over the mics). A bin of one direction is that source's; a
    // diffuse bin (no direction coherent with it: reverberation, background) is shared by all
    // as the background each source is heard against; a coherent bin that two directions
    // explain alike (close directions, low frequencies) is nobody's.
    const float p = static_cast<float>(norm / m);
    band_energy += p;
    const bool coherent = coherence_[best] >= options_.min_bin_coherence;
    const bool owned = coherent && coherence_[best] - second >= options_.bin_margin;
    for (size_t t = 0; t < n; ++t)
      powers[t][k] = owned ? (t == best ? p : -1.0f) : (coherent ? -1.0f : p);
    if (owned) owned_energy[best] += p;
  }
  // Bins of other sources stay masked out (-1), not zero: the spectral shape is this track's.
  // A direction that holds most of the frame's energy sounds in it, reported or not.
  for (size_t t = 0; t < n; ++t) {
    if (only < n && t != only) continue;
    tracks_[t].classifier->AddFrame(
        powers[t], end_sample,
        options_.dominant_share > 0 && owned_energy[t] >= options_.dominant_share * band_energy ? 1
                                                                                                : 0,
        owned_energy[t]);
  }
}

std::vector<SoundClassEstimate> DirectionalClassifier::Observe(
    int64_t begin_sample, int64_t end_sample, const std::vector<Direction>& directions) {
  const double rate = geometry_.sample_rate_hz;
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const ClassTrack& t) {
                                 return (end_sample - t.last_sample) / rate > options_.forget_s;
                               }),
                tracks_.end());
  std::vector<SoundClassEstimate> out;
  std::vector<char> used(tracks_.size(), 0);
  for (const Direction& d : directions) {
    int best = -1;
    double best_rad = DegToRad(options_.gate_deg);
    for (size_t t = 0; t < tracks_.size(); ++t) {
      if (used[t]) continue;
      const double a = AngularDistanceRad(geometry_, kind_, tracks_[t].direction, d);
      if (a < best_rad) {
        best_rad = a;
        best = static_cast<int>(t);
      }
    }
    if (best < 0) {
      if (static_cast<int>(tracks_.size()) >= options_.max_tracks) {
        // The track heard least recently makes room.
        auto oldest = std::min_element(
            tracks_.begin(), tracks_.end(),
            [](const ClassTrack& a, const ClassTrack& b) { return a.last_sample < b.last_sample; });
        const size_t index = static_cast<size_t>(oldest - tracks_.begin());
        tracks_.erase(oldest);
        used.erase(used.begin() + index);
      }
      ClassTrack t;
      t.classifier = std::make_unique<SoundClassifier>(options_, geometry_.sample_rate_hz);
      tracks_.push_back(std::move(t));
      used.push_back(0);
      best = static_cast<int>(tracks_.size()) - 1;
    }
    const bool started = tracks_[best].classifier->frames_seen() == 0;
    ClassTrack& t = tracks_[best];
    used[best] = 1;
    t.direction = d;
    t.unit = geometry_.Unit(kind_, d);
    const Eigen::VectorXd delays = geometry_.Delays(t.unit);
    t.conj_steering.resize(bin_hi_ - bin_lo_ + 1, geometry_.num_mics());
    for (int k = bin_lo_; k <= bin_hi_; ++k) {
      const double w = 2 * M_PI * k * geometry_.sample_rate_hz / options_.fft_size;
      for (int i = 0; i < geometry_.num_mics(); ++i)
        t.conj_steering(k - bin_lo_, i) = std::polar(1.0, w * delays(i));
    }
    t.last_sample = end_sample;
    if (started)
      for (const RecentFrame& f : recent_)
        if (f.end_sample > begin_sample) AddFrame(f.spectra, f.end_sample, best);
    t.classifier->MarkPresent(begin_sample, end_sample);
    out.push_back(t.classifier->Classify());
  }
  return out;
}

std::vector<SoundClassEstimate> DirectionalClassifier::Lookup(
    const std::vector<Direction>& directions) const {
  std::vector<SoundClassEstimate> out;
  for (const Direction& d : directions) {
    const ClassTrack* best = nullptr;
    double best_rad = DegToRad(options_.gate_deg);
    for (const ClassTrack& t : tracks_) {
      const double a = AngularDistanceRad(geometry_, kind_, t.direction, d);
      if (a < best_rad) {
        best_rad = a;
        best = &t;
      }
    }
    out.push_back(best ? best->classifier->Classify() : SoundClassEstimate());
  }
  return out;
}

}  // namespace sound
}  // namespace sarmap
