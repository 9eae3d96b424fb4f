#pragma once
// Multichannel audio files through libsndfile: WAV/FLAC/... (header gives rate and channels)
// and headerless raw PCM (rate, channels and format given by the caller).

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace sarmap {
namespace audio {

class AudioFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How to read a headerless file; ignored for files with a header.
struct RawFormat {
  int sample_rate_hz = 16000;
  int num_channels = 1;
  std::string encoding = "s16le";  // s16le | s32le | f32le
};

// Streams interleaved int16 blocks from a file.
class AudioFileReader {
 public:
  // Opens `path`; files ending in .raw/.pcm (or when force_raw) are read with `raw`.
  // Throws AudioFileError with the path and libsndfile's reason.
  explicit AudioFileReader(const std::string& path, const RawFormat& raw = RawFormat(),
                           bool force_raw = false);
  ~AudioFileReader();
  AudioFileReader(const AudioFileReader&) = delete;
  AudioFileReader& operator=(const AudioFileReader&) = delete;

  int sample_rate_hz() const { return sample_rate_hz_; }
  int num_channels() const { return num_channels_; }
  int64_t num_frames() const { return num_frames_; }  // per channel; -1 if unknown
  // Reads up to `frames` frames (interleaved) into `out` (resized); returns frames read, 0 at
  // end of file.
  int64_t Read(int64_t frames, std::vector<int16_t>* out);
  // Rewinds to the first frame (for looping).
  void Rewind();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  int sample_rate_hz_ = 0;
  int num_channels_ = 0;
  int64_t num_frames_ = -1;
};

// A whole file in memory as float in [-1, 1), channel-major: data[c][i].
struct AudioBuffer {
  int sample_rate_hz = 0;
  std::vector<std::vector<float>> channels;
  int num_channels() const { return static_cast<int>(channels.size()); }
  size_t num_frames() const { return channels.empty() ? 0 : channels[0].size(); }
};
AudioBuffer ReadAudioFile(const std::string& path, const RawFormat& raw = RawFormat());
// Writes 16-bit PCM WAV (clipping to full scale).
void WriteWav(const std::string& path, const AudioBuffer& buffer);

// Interleaves channel-major float samples into int16 (clipped).
std::vector<int16_t> ToInterleavedInt16(const std::vector<std::vector<float>>& channels,
                                        size_t begin, size_t count);

}  // namespace audio
}  // namespace sarmap
