#include "sim/sound_sources.h"

#include <sndfile.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sys/stat.h>
#include <unistd.h>
#include <cctype>

namespace sarmap {
namespace sim {
namespace {

void TrimAndNormalise(std::vector<float>* clip) {
  float peak = 0;
  for (float v : *clip) peak = std::max(peak, std::abs(v));
  if (peak <= 0) {
    clip->clear();
    return;
  }
  const float threshold = 0.02f * peak;
  size_t a = 0, b = clip->size();
  while (a < b && std::abs((*clip)[a]) < threshold) ++a;
  while (b > a && std::abs((*clip)[b - 1]) < threshold) --b;
  std::vector<float> out(clip->begin() + a, clip->begin() + b);
  double energy = 0;
  for (float v : out) energy += static_cast<double>(v) * v;
  const double rms = std::sqrt(energy / std::max<size_t>(1, out.size()));
  for (float& v : out) v = static_cast<float>(v / rms);
  *clip = std::move(out);
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::vector<float> Resample(const std::vector<float>& in, double from_hz, double to_hz) {
  if (std::abs(from_hz - to_hz) < 1e-9) return in;
  const double ratio = from_hz / to_hz;            // input samples per output sample
  const double cutoff = std::min(1.0, to_hz / from_hz);  // anti-alias when downsampling
  const int half = static_cast<int>(std::ceil(16 / cutoff));
  const size_t n_out = static_cast<size_t>(std::floor(in.size() / ratio));
  std::vector<float> out(n_out);
  for (size_t k = 0; k < n_out; ++k) {
    const double centre = k * ratio;
    const int c = static_cast<int>(std::floor(centre));
    double acc = 0;
    for (int n = c - half + 1; n <= c + half; ++n) {
      if (n < 0 || n >= static_cast<int>(in.size())) continue;
      const double x = (n - centre) * cutoff;
      const double sinc = std::abs(x) < 1e-9 ? 1.0 : std::sin(M_PI * x) / (M_PI * x);
      const double window = 0.5 * (1 + std::cos(M_PI * (n - centre) / (half + 1)));
      acc += in[n] * cutoff * sinc * window;
    }
    out[k] = static_cast<float>(acc);
  }
  return out;
}

std::vector<float> LoadClip(const std::string& path, int sample_rate_hz, std::string* error) {
  std::vector<float> clip;
  double rate = 16000;
  if (EndsWith(path, ".raw")) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      *error = "cannot open " + path;
      return {};
    }
    int16_t v;
    while (in.read(reinterpret_cast<char*>(&v), 2)) clip.push_back(v / 32768.0f);
  } else {
    SF_INFO info{};
    SNDFILE* file = sf_open(path.c_str(), SFM_READ, &info);
    if (!file) {
      *error = "cannot read " + path + ": " + sf_strerror(nullptr);
      return {};
    }
    std::vector<float> frames(static_cast<size_t>(info.frames) * info.channels);
    sf_readf_float(file, frames.data(), info.frames);
    sf_close(file);
    rate = info.samplerate;
    clip.resize(info.frames);
    for (sf_count_t k = 0; k < info.frames; ++k) clip[k] = frames[static_cast<size_t>(k) * info.channels];
  }
  clip = Resample(clip, rate, sample_rate_hz);
  TrimAndNormalise(&clip);
  if (clip.empty()) *error = path + " is silent";
  return clip;
}

std::vector<float> EspeakClip(const std::string& phrase, const std::string& cache_dir,
                              int sample_rate_hz, std::string* error) {
  ::mkdir(cache_dir.c_str(), 0700);
  const std::string wav = cache_dir + "/espeak_" + std::to_string(std::hash<std::string>()(phrase)) + ".wav";
  struct stat st {};
  if (::stat(wav.c_str(), &st) != 0 || st.st_size < 100) {
    if (std::system("command -v espeak-ng > /dev/null 2>&1") != 0) {
      *error = "espeak-ng not installed: phrase '" + phrase + "' skipped";
      return {};
    }
    std::string quoted;
    for (char ch : phrase) {
      if (std::isalnum(static_cast<unsigned char>(ch)) || ch == ' ' || ch == ',' || ch == '.' || ch == '!' || ch == '?' || ch == '\'') {
        quoted += ch;
      }
    }
    const std::string tmp = wav + ".tmp." + std::to_string(::getpid());
    const std::string cmd = "espeak-ng -w '" + tmp + "' \"" + quoted + "\" > /dev/null 2>&1";
    if (std::system(cmd.c_str()) != 0 || std::rename(tmp.c_str(), wav.c_str()) != 0) {
      std::remove(tmp.c_str());
      *error = "espeak-ng failed for phrase '" + phrase + "'";
      return {};
    }
  }
  return LoadClip(wav, sample_rate_hz, error);
}

SourceSignal::SourceSignal(const SoundSource& source, std::vector<std::vector<float>> clips,
                           int sample_rate_hz, uint64_t seed)
    : source_(source), clips_(std::move(clips)), rate_(sample_rate_hz), rng_(seed) {
  for (const auto& c : clips_) cycle_s_ += static_cast<double>(c.size()) / rate_ + source_.gap_s;
  // Normalise the synthetic signals to unit RMS over a few seconds.
  if (source_.kind == SourceKind::kMusic || source_.kind == SourceKind::kAlarm) {
    double energy = 0;
    const int n = static_cast<int>(std::max(4.0, 2 * source_.beep_period_s) *
                                   rate_);  // tune 1.76 s, alarm 1 s
    for (int k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) / rate_;
      const double v = source_.kind == SourceKind::kMusic ? Music(t) : Alarm(t);
      energy += v * v;
    }
    (source_.kind == SourceKind::kMusic ? music_norm_ : alarm_norm_) = 1.0 / std::sqrt(energy / n);
  }
}

bool SourceSignal::ScheduledAt(double t) const {
  if (t < source_.start_s || t >= source_.stop_s) return false;
  const double since = t - source_.start_s;
  if (source_.every_s > 0) {
    const double in_period = std::fmod(since, source_.every_s);
    return source_.duration_s <= 0 || in_period < source_.duration_s;
  }
  return source_.duration_s <= 0 || since < source_.duration_s;
}

bool SourceSignal::VoiceAt(double t, int* clip, double* clip_start) const {
  if (clips_.empty() || t < source_.start_s || t >= source_.stop_s) return false;
  const double since = t - source_.start_s;
  if (source_.continuous) {
    if (cycle_s_ <= 0) return false;
    const double cycles = std::floor(since / cycle_s_);
    double at = since - cycles * cycle_s_;
    double begin = source_.start_s + cycles * cycle_s_;
    for (size_t k = 0; k < clips_.size(); ++k) {
      const double len = static_cast<double>(clips_[k].size()) / rate_;
      if (at < len) {
        *clip = static_cast<int>(k);
        *clip_start = begin;
        return true;
      }
      at -= len + source_.gap_s;
      begin += len + source_.gap_s;
      if (at < 0) return false;
    }
    return false;
  }
  int64_t event = 0;
  if (source_.every_s > 0) event = static_cast<int64_t>(std::floor(since / source_.every_s));
  else if (since < 0) return false;
  const double begin = source_.start_s + event * source_.every_s;
  const int k = static_cast<int>(event % static_cast<int64_t>(clips_.size()));
  const double len = static_cast<double>(clips_[k].size()) / rate_;
  double end = begin + len;
  if (source_.duration_s > 0) end = std::min(end, begin + source_.duration_s);
  if (t >= end) return false;
  *clip = k;
  *clip_start = begin;
  return true;
}

bool SourceSignal::ActiveAt(double t) const {
  if (source_.kind == SourceKind::kVoice) {
    int clip;
    double start;
    return VoiceAt(t, &clip, &start);
  }
  return ScheduledAt(t);
}

// A repeating eight-note phrase with a bass line: harmonic tones with a plucked envelope,
// like a phone's ring tune.
double SourceSignal::Music(double t) const {
  static const double kNotes[8] = {523.25, 659.25, 783.99, 1046.5, 783.99, 659.25, 587.33, 698.46};
  const double note_s = 0.22;
  const int idx = static_cast<int>(std::floor(t / note_s)) % 8;
  const double local = std::fmod(t, note_s);
  const double env = std::exp(-local * 9.0) * std::min(1.0, local * 200.0);
  const double f = kNotes[idx];
  double v = 0;
  for (int h = 1; h <= 4; ++h) v += std::sin(2 * M_PI * f * h * t) / (h * h);
  const double bass_f = idx < 4 ? 130.81 : 146.83;
  v = v * env + 0.4 * std::sin(2 * M_PI * bass_f * t) * std::exp(-std::fmod(t, 4 * note_s) * 2.0);
  return v;
}

// Two-tone alarm (960 / 770 Hz, half a second each), band-limited square wave; or a beeper:
// a tone_hz sine with a weak 2nd harmonic (a piezo sounder), on for half of beep_period_s.
double SourceSignal::Alarm(double t) const {
  if (source_.tone_hz > 0) {
    const double phase = std::fmod(t, source_.beep_period_s) / source_.beep_period_s;
    if (phase >= 0.5) return 0.0;
    return std::sin(2 * M_PI * source_.tone_hz * t) +
           0.2 * std::sin(4 * M_PI * source_.tone_hz * t);
  }
  const double f = std::fmod(t, 1.0) < 0.5 ? 960.0 : 770.0;
  double v = 0;
  for (int h = 1; h <= 7; h += 2) v += std::sin(2 * M_PI * f * h * t) / h;
  return v;
}

bool SourceSignal::Render(int64_t first, int n, float* out) {
  bool any = false;
  const double level = 1.0;
  for (int k = 0; k < n; ++k) {
    const double t = static_cast<double>(first + k) / rate_;
    double v = 0;
    switch (source_.kind) {
      case SourceKind::kVoice: {
        int clip;
        double start;
        if (VoiceAt(t, &clip, &start)) {
          const int64_t idx = first + k - static_cast<int64_t>(std::llround(start * rate_));
          if (idx >= 0 && idx < static_cast<int64_t>(clips_[clip].size())) v = clips_[clip][idx];
        }
        break;
      }
      case SourceKind::kMusic:
        if (ScheduledAt(t)) v = Music(t) * music_norm_;
        break;
      case SourceKind::kAlarm:
        if (ScheduledAt(t)) v = Alarm(t) * alarm_norm_;
        break;
      case SourceKind::kNoise: {
        // Brown-ish (one-pole low-pass, like fans and air conditioning) plus some white, and
        // a hum with its 2nd harmonic (motors, transformers).
        const double w = normal_(rng_);
        lowpass_ = 0.97 * lowpass_ + 0.03 * w;
        if (ScheduledAt(t)) {
          const double brown = lowpass_ / std::sqrt(0.03 / 1.97);
          v = 0.8 * brown + 0.6 * normal_(rng_);
          if (source_.hum_hz > 0) v += 0.8 * std::sin(2 * M_PI * source_.hum_hz * t) + 0.4 * std::sin(4 * M_PI * source_.hum_hz * t);
          v /= source_.hum_hz > 0 ? std::sqrt(1.0 + 0.4) : 1.0;
        }
        break;
      }
    }
    out[k] = static_cast<float>(level * v);
    any = any || v != 0.0;
  }
  return any;
}

}  // namespace sim
}  // namespace sarmap
