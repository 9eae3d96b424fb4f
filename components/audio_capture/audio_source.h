#pragma once
// Sources of multichannel audio for sarmap-audio-capture (no LCM): an ALSA capture device of
// any channel count and rate, or a multichannel WAV/raw file played at real-time pace (or
// faster). Each source has its own clock and a running sample counter; lost samples
// (overruns, dropouts) are counted, never hidden.

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "audio_capture/audio_file.h"
#include "common/options.h"

namespace sarmap {
namespace audio {

class AudioSourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CaptureOptions {
  std::string source = "file";        // alsa | file
  std::string device = "default";     // ALSA PCM name (hw:1,0, plughw:CARD=Array,DEV=0, ...)
  std::string file;                   // WAV/FLAC/raw path (source file)
  std::string device_id = "";         // stable name in audio_frame_t; "" = derived from device/file
  std::string channel = "AUDIO";      // output channel; "AUDIO_*" = AUDIO_<DEVICE_ID>
  int sample_rate_hz = 16000;         // expected/requested; 0 = take the file's
  int num_channels = 4;               // expected/requested; 0 = take the file's
  double block_s = 0.032;             // samples per published message
  double speed = 1.0;                 // file pacing: 1 real time, 2 twice as fast, 0 as fast as possible
  bool loop = false;                  // file: start again at the end
  std::string raw_encoding = "s16le"; // raw files: s16le | s32le | f32le
  int64_t start_utime = 0;            // file: utime of its first sample; 0 = wall clock at start
  int alsa_period_frames = 256;
  int alsa_buffer_periods = 8;
  double clip_warn_fraction = 0.001;  // warn when more samples than this are at full scale
  double silence_dbfs = -80;          // a channel below this RMS is silent
  double silence_warn_s = 2.0;        // warn when a channel stays silent this long

  template <class V>
  void Visit(V& v) {
    v("source", source, "alsa or file", OneOf({"alsa", "file"}));
    v("device", device, "ALSA capture PCM (arecord -L lists them)");
    v("file", file, "audio file for source file (WAV/FLAC; .raw/.pcm are headerless)");
    v("device_id", device_id, "stable device name published in audio_frame_t ('' = from device/file)");
    v("channel", channel, "LCM channel; AUDIO_* publishes on AUDIO_<DEVICE_ID>");
    v("sample_rate_hz", sample_rate_hz, "requested (ALSA) or expected (file) rate; 0 = the file's",
      AtLeast(0));
    v("num_channels", num_channels, "requested (ALSA) or expected (file) channels; 0 = the file's",
      InRange(0, 64));
    v("block_s", block_s, "audio per message", InRange(0.001, 1.0));
    v("speed", speed, "file pacing: 1 = real time, 0 = as fast as possible", NonNegative());
    v("loop", loop, "file: loop forever");
    v("raw_encoding", raw_encoding, "headerless files: s16le, s32le or f32le",
      OneOf({"s16le", "s32le", "f32le"}));
    v("start_utime", start_utime, "file: utime of the first sample (0 = wall clock at start)");
    v("alsa_period_frames", alsa_period_frames, "ALSA period size", AtLeast(16));
    v("alsa_buffer_periods", alsa_buffer_periods, "ALSA buffer size in periods", AtLeast(2));
    v("clip_warn_fraction", clip_warn_fraction, "warn when this fraction of a block is clipped",
      InRange(0, 1));
    v("silence_dbfs", silence_dbfs, "channels quieter than this are silent");
    v("silence_warn_s", silence_warn_s, "warn after a channel is silent this long", Positive());
  }
  void Validate(common::Validator& check) const {
    check.That(source != "file" || !file.empty(), "file", "needed for source file");
    check.That(source != "alsa" || sample_rate_hz > 0, "sample_rate_hz", "ALSA needs a rate");
    check.That(source != "alsa" || num_channels > 0, "num_channels", "ALSA needs a channel count");
  }
};

// One block read from a source.
struct AudioBlock {
  int64_t utime = 0;                // capture time of the first sample
  int64_t first_sample_index = 0;   // since the source opened (lost samples included)
  int64_t overrun_samples = 0;      // cumulative lost samples
  int num_channels = 0;
  int num_frames = 0;
  std::vector<int16_t> samples;     // interleaved
};

class AudioSource {
 public:
  virtual ~AudioSource() = default;
  virtual int sample_rate_hz() const = 0;
  virtual int num_channels() const = 0;
  virtual std::string device_id() const = 0;
  // Reads the next block (blocking for devices and paced files). False at end of stream.
  virtual bool Read(int frames, AudioBlock* block) = 0;
};

// Opens the configured source; throws AudioSourceError with a clear message (absent device,
// unsupported channel count or rate, unreadable file, channel-count/rate mismatch).
std::unique_ptr<AudioSource> OpenAudioSource(const CaptureOptions& options);
std::unique_ptr<AudioSource> OpenFileSource(const CaptureOptions& options);
std::unique_ptr<AudioSource> OpenAlsaSource(const CaptureOptions& options);

// Checks the signal of each channel: clipping, silence (dead microphones, muted cards).
class SignalChecker {
 public:
  SignalChecker(const CaptureOptions& options, int sample_rate_hz, int num_channels);
  // Returns warnings for this block (empty when fine); each warning once per onset.
  std::vector<std::string> Check(const AudioBlock& block);
  int64_t clipped_samples() const { return clipped_total_; }
  const std::vector<double>& silent_seconds() const { return silent_s_; }

 private:
  CaptureOptions options_;
  int rate_;
  std::vector<double> silent_s_;
  std::vector<bool> silence_reported_;
  int64_t clipped_total_ = 0;
  double clip_report_s_ = -1e9, time_s_ = 0;
};

// "AUDIO_*" -> "AUDIO_<ID>" with the id upper-cased and non-alphanumerics as '_'.
std::string OutputChannel(const std::string& pattern, const std::string& device_id);

}  // namespace audio
}  // namespace sarmap
