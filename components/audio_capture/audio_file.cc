#include "audio_capture/audio_file.h"

#include <sndfile.h>

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace audio {

struct AudioFileReader::Impl {
  SNDFILE* file = nullptr;
};

namespace {
bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

AudioFileReader::AudioFileReader(const std::string& path, const RawFormat& raw, bool force_raw)
    : impl_(new Impl), path_(path) {
  SF_INFO info{};
  const bool is_raw = force_raw || EndsWith(path, ".raw") || EndsWith(path, ".pcm");
  if (is_raw) {
    if (raw.sample_rate_hz <= 0 || raw.num_channels <= 0)
      throw AudioFileError(path + ": raw file needs a positive sample rate and channel count");
    info.samplerate = raw.sample_rate_hz;
    info.channels = raw.num_channels;
    int subtype = 0;
    if (raw.encoding == "s16le") subtype = SF_FORMAT_PCM_16;
    else if (raw.encoding == "s32le") subtype = SF_FORMAT_PCM_32;
    else if (raw.encoding == "f32le") subtype = SF_FORMAT_FLOAT;
    else throw AudioFileError(path + ": unknown raw encoding '" + raw.encoding +
                              "' (s16le, s32le or f32le)");
    info.format = SF_FORMAT_RAW | subtype | SF_ENDIAN_LITTLE;
  }
  impl_->file = sf_open(path.c_str(), SFM_READ, &info);
  if (!impl_->file) throw AudioFileError(path + ": cannot open audio file: " + sf_strerror(nullptr));
  sample_rate_hz_ = info.samplerate;
  num_channels_ = info.channels;
  num_frames_ = info.frames;
  if (num_channels_ <= 0 || sample_rate_hz_ <= 0)
    throw AudioFileError(path + ": file reports " + std::to_string(num_channels_) + " channels at " +
                         std::to_string(sample_rate_hz_) + " Hz");
}

AudioFileReader::~AudioFileReader() {
  if (impl_ && impl_->file) sf_close(impl_->file);
}

int64_t AudioFileReader::Read(int64_t frames, std::vector<int16_t>* out) {
  out->resize(static_cast<size_t>(frames * num_channels_));
  const sf_count_t got = sf_readf_short(impl_->file, out->data(), frames);
  if (got < 0) throw AudioFileError(path_ + ": read error: " + sf_strerror(impl_->file));
  out->resize(static_cast<size_t>(got * num_channels_));
  return got;
}

void AudioFileReader::Rewind() { sf_seek(impl_->file, 0, SEEK_SET); }

AudioBuffer ReadAudioFile(const std::string& path, const RawFormat& raw) {
  AudioFileReader reader(path, raw);
  AudioBuffer buffer;
  buffer.sample_rate_hz = reader.sample_rate_hz();
  const int nc = reader.num_channels();
  buffer.channels.assign(nc, {});
  std::vector<int16_t> block;
  while (reader.Read(8192, &block) > 0) {
    const size_t frames = block.size() / nc;
    for (int c = 0; c < nc; ++c) {
      auto& ch = buffer.channels[c];
      for (size_t i = 0; i < frames; ++i) ch.push_back(block[i * nc + c] / 32768.0f);
    }
  }
  return buffer;
}

std::vector<int16_t> ToInterleavedInt16(const std::vector<std::vector<float>>& channels,
                                        size_t begin, size_t count) {
  const size_t nc = channels.size();
  std::vector<int16_t> out(nc * count, 0);
  for (size_t c = 0; c < nc; ++c)
    for (size_t i = 0; i < count && begin + i < channels[c].size(); ++i) {
      const float v = std::round(channels[c][begin + i] * 32768.0f);
      out[i * nc + c] = static_cast<int16_t>(std::clamp(v, -32768.0f, 32767.0f));
    }
  return out;
}

void WriteWav(const std::string& path, const AudioBuffer& buffer) {
  SF_INFO info{};
  info.samplerate = buffer.sample_rate_hz;
  info.channels = buffer.num_channels();
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* f = sf_open(path.c_str(), SFM_WRITE, &info);
  if (!f) throw AudioFileError(path + ": cannot write: " + sf_strerror(nullptr));
  const auto data = ToInterleavedInt16(buffer.channels, 0, buffer.num_frames());
  sf_writef_short(f, data.data(), static_cast<sf_count_t>(buffer.num_frames()));
  sf_close(f);
}

}  // namespace audio
}  // namespace sarmap
