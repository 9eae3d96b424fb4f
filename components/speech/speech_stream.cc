#include "speech/speech_stream.h"

#include <algorithm>
#include <cmath>

#include "common/time.h"
#include "sound_localisation/localiser.h"

namespace sarmap {
namespace speech {

SpeechStream::SpeechStream(const SpeechNodeOptions& options, const common::MicArrayOptions& array)
    : options_(options) {
  geometry_ = sound::ArrayGeometry::FromOptions(array);
  kind_ = sound::ResolveKind(geometry_, options.search);
  processor_ = std::make_unique<SpeechProcessor>(geometry_, kind_, options.speech);
}

int64_t SpeechStream::ToUtime(int64_t sample) const {
  return anchor_utime_ +
         common::SecondsToUtime((sample - anchor_sample_) / geometry_.sample_rate_hz);
}

void SpeechStream::OnDoa(const sarmap::doa_t& msg, const std::string& device,
                         std::vector<std::string>* warnings) {
  if (anchor_sample_ < 0 || (!device.empty() && msg.device_id != device)) return;
  const double rate = geometry_.sample_rate_hz;
  // In double and clamped: a stamp near the int64 limits must not overflow (the processor
  // drops DOAs far ahead of the audio, and a track far behind times out).
  const double offset_samples = std::clamp(
      (static_cast<double>(msg.header.utime) - static_cast<double>(anchor_utime_)) * 1e-6 * rate,
      -1e12, 1e12);
  const int64_t sample = anchor_sample_ + static_cast<int64_t>(std::llround(offset_samples));
  for (const auto& s : msg.sources) {
    if (s.track_id < 0) continue;
    if (s.kind != static_cast<int8_t>(kind_)) {
      warnings->push_back("DOA kind " + std::to_string(s.kind) +
                          " does not match this node's search (" + options_.search + ")");
      continue;
    }
    Eigen::Matrix2d cov;
    cov << s.covariance[0], s.covariance[1], s.covariance[2], s.covariance[3];
    if (!processor_->UpdateTrack(s.track_id, {s.azimuth_rad, s.elevation_rad}, cov, sample))
      warnings->push_back("DOA stamped more than " +
                          std::to_string(options_.speech.max_doa_ahead_s) +
                          " s ahead of the audio; dropped");
  }
}

void SpeechStream::OnAudio(const int16_t* data, int frames, int block_channels, int64_t utime,
                           const std::string& device, std::vector<sarmap::speech_event_t>* events,
                           std::vector<sarmap::people_detections_t>* people) {
  anchor_sample_ = processor_->samples_seen();
  anchor_utime_ = utime;
  results_.clear();
  processor_->Push(data, frames, block_channels, &results_);
  Emit(device, events, people);
}

void SpeechStream::Flush(const std::string& device, std::vector<sarmap::speech_event_t>* events,
                         std::vector<sarmap::people_detections_t>* people) {
  results_.clear();
  processor_->Flush(&results_);
  Emit(device, events, people);
}

void SpeechStream::Emit(const std::string& device, std::vector<sarmap::speech_event_t>* events,
                        std::vector<sarmap::people_detections_t>* people) const {
  for (const auto& r : results_) {
    const sarmap::speech_event_t e =
        ToSpeechEvent(r, ToUtime(r.start_sample), ToUtime(r.end_sample));
    events->push_back(e);
    if (r.keyword.empty() || !r.has_direction) continue;
    people->push_back(ToPeopleAudio(r, device, e.end_utime));
  }
}

}  // namespace speech
}  // namespace sarmap
