#include "audio_capture/audio_source.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "common/time.h"

namespace sarmap {
namespace audio {

std::string OutputChannel(const std::string& pattern, const std::string& device_id) {
  if (pattern.size() < 2 || pattern.substr(pattern.size() - 2) != "_*") return pattern;
  std::string id;
  for (char c : device_id) id += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::toupper(c)) : '_';
  return pattern.substr(0, pattern.size() - 1) + id;
}

namespace {

class FileSource : public AudioSource {
 public:
  explicit FileSource(const CaptureOptions& o) : options_(o) {
    RawFormat raw;
    raw.sample_rate_hz = o.sample_rate_hz > 0 ? o.sample_rate_hz : 16000;
    raw.num_channels = o.num_channels > 0 ? o.num_channels : 1;
    raw.encoding = o.raw_encoding;
    try {
      reader_ = std::make_unique<AudioFileReader>(o.file, raw);
    } catch (const AudioFileError& e) {
      throw AudioSourceError(e.what());
    }
    if (o.num_channels > 0 && reader_->num_channels() != o.num_channels)
      throw AudioSourceError(o.file + ": has " + std::to_string(reader_->num_channels()) + " channels, expected " +
                             std::to_string(o.num_channels) + " (set num_channels to 0 to accept the file's)");
    if (o.sample_rate_hz > 0 && reader_->sample_rate_hz() != o.sample_rate_hz)
      throw AudioSourceError(o.file + ": sample rate is " + std::to_string(reader_->sample_rate_hz()) +
                             " Hz, expected " + std::to_string(o.sample_rate_hz) +
                             " Hz (resample it, e.g. sox in.wav -r " + std::to_string(o.sample_rate_hz) +
                             " out.wav, or set sample_rate_hz to 0)");
    id_ = o.device_id;
    if (id_.empty()) {
      id_ = o.file.substr(o.file.find_last_of('/') + 1);
      id_ = id_.substr(0, id_.find('.'));
    }
    start_utime_ = o.start_utime ? o.start_utime : common::WallClockUtime();
  }
  int sample_rate_hz() const override { return reader_->sample_rate_hz(); }
  int num_channels() const override { return reader_->num_channels(); }
  std::string device_id() const override { return id_; }

  bool Read(int frames, AudioBlock* block) override {
    int64_t got = reader_->Read(frames, &block->samples);
    if (got == 0 && options_.loop) {
      reader_->Rewind();
      got = reader_->Read(frames, &block->samples);
    }
    if (got == 0) return false;
    const double rate = sample_rate_hz();
    block->num_channels = num_channels();
    block->num_frames = static_cast<int>(got);
    block->first_sample_index = next_index_;
    block->overrun_samples = 0;
    block->utime = start_utime_ + common::SecondsToUtime(next_index_ / rate);
    next_index_ += got;
    if (options_.speed > 0) {
      // Released when its last sample would have been captured.
      if (!pacing_started_) {
        pace_start_ = std::chrono::steady_clock::now();
        pacing_started_ = true;
      }
      const auto due = pace_start_ + std::chrono::duration<double>(next_index_ / rate / options_.speed);
      std::this_thread::sleep_until(due);
    }
    return true;
  }

 private:
  CaptureOptions options_;
  std::unique_ptr<AudioFileReader> reader_;
  std::string id_;
  int64_t start_utime_ = 0, next_index_ = 0;
  bool pacing_started_ = false;
  std::chrono::steady_clock::time_point pace_start_;
};

}  // namespace

std::unique_ptr<AudioSource> OpenFileSource(const CaptureOptions& options) {
  return std::make_unique<FileSource>(options);
}

std::unique_ptr<AudioSource> OpenAudioSource(const CaptureOptions& options) {
  if (options.source == "alsa") return OpenAlsaSource(options);
  if (options.source == "file") return OpenFileSource(options);
  throw AudioSourceError("unknown audio source '" + options.source + "' (alsa or file)");
}

SignalChecker::SignalChecker(const CaptureOptions& options, int rate, int num_channels)
    : options_(options), rate_(rate), silent_s_(num_channels, 0.0), silence_reported_(num_channels, false) {}

std::vector<std::string> SignalChecker::Check(const AudioBlock& b) {
  std::vector<std::string> warnings;
  const int nc = b.num_channels;
  if (nc != static_cast<int>(silent_s_.size())) {
    warnings.push_back("block has " + std::to_string(nc) + " channels, expected " + std::to_string(silent_s_.size()));
    return warnings;
  }
  const double dt = static_cast<double>(b.num_frames) / rate_;
  time_s_ += dt;
  int64_t clipped = 0;
  std::vector<double> energy(nc, 0.0);
  for (int i = 0; i < b.num_frames; ++i)
    for (int c = 0; c < nc; ++c) {
      const int v = b.samples[static_cast<size_t>(i) * nc + c];
      clipped += (v >= 32767 || v <= -32768);
      energy[c] += static_cast<double>(v) * v;
    }
  clipped_total_ += clipped;
  const double total = static_cast<double>(b.num_frames) * nc;
  if (total > 0 && clipped > options_.clip_warn_fraction * total && time_s_ - clip_report_s_ > 5.0) {
    clip_report_s_ = time_s_;
    warnings.push_back("input clipped: " + std::to_string(clipped) + " of " + std::to_string(static_cast<int64_t>(total)) +
                       " samples at full scale (lower the capture gain); " + std::to_string(clipped_total_) + " so far");
  }
  const double threshold = std::pow(10.0, options_.silence_dbfs / 20.0) * 32768.0;
  for (int c = 0; c < nc; ++c) {
    const double rms = b.num_frames ? std::sqrt(energy[c] / b.num_frames) : 0.0;
    if (rms < threshold) {
      silent_s_[c] += dt;
      if (silent_s_[c] >= options_.silence_warn_s && !silence_reported_[c]) {
        silence_reported_[c] = true;
        warnings.push_back("channel " + std::to_string(c) + " silent for " + std::to_string(silent_s_[c]).substr(0, 4) +
                           " s (" + (rms == 0 ? "all zeros: dead microphone, muted or wrong channel map" : "below " +
                           std::to_string(static_cast<int>(options_.silence_dbfs)) + " dBFS") + ")");
      }
    } else {
      if (silence_reported_[c]) warnings.push_back("channel " + std::to_string(c) + " has signal again");
      silent_s_[c] = 0;
      silence_reported_[c] = false;
    }
  }
  return warnings;
}

}  // namespace audio
}  // namespace sarmap
