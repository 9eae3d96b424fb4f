#pragma once
// The signals of sound emitters: recorded or espeak-ng voices on a schedule, synthesised
// music, an alarm, noise. Every signal has unit RMS while active; the audio simulator scales
// it to the source's level.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "sim/world.h"

namespace sarmap {
namespace sim {

// Loads a mono clip (WAV/FLAC via libsndfile, or .raw s16le 16 kHz), resampled to
// sample_rate_hz, trimmed of leading/trailing silence and normalised to unit RMS. Empty
// with `error` set on failure.
std::vector<float> LoadClip(const std::string& path, int sample_rate_hz, std::string* error);
// Renders `phrase` with `espeak-ng -w` into cache_dir (reused when present); empty with
// `error` set when espeak-ng is missing or fails.
std::vector<float> EspeakClip(const std::string& phrase, const std::string& cache_dir,
                              int sample_rate_hz, std::string* error);
// Windowed-sinc resampling of a whole clip.
std::vector<float> Resample(const std::vector<float>& in, double from_hz, double to_hz);

class SourceSignal {
 public:
  // clips: unit-RMS voice clips at sample_rate_hz (voices only; may be empty when none could
  // be loaded: the voice is then silent).
  SourceSignal(const SoundSource& source, std::vector<std::vector<float>> clips,
               int sample_rate_hz, uint64_t seed);
  // Writes n samples from sample index `first` (time first / rate). Must be called with
  // consecutive ranges (noise generators keep state). Returns false when all are silent.
  bool Render(int64_t first, int n, float* out);
  bool ActiveAt(double t_s) const;
  const SoundSource& source() const { return source_; }

 private:
  // Voice: which clip plays at t and from which sample; false when silent.
  bool VoiceAt(double t_s, int* clip, double* clip_start_s) const;
  bool ScheduledAt(double t_s) const;
  double Music(double t_s) const;
  double Alarm(double t_s) const;

  SoundSource source_;
  std::vector<std::vector<float>> clips_;
  int rate_;
  double cycle_s_ = 0;  // continuous voices: clips + gaps
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  double lowpass_ = 0;
  double music_norm_ = 1, alarm_norm_ = 1;
};

}  // namespace sim
}  // namespace sarmap
