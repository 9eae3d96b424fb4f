#pragma once
// What sarmap-speech and sarmap-log-speech share: the node's options and the conversion of a
// SpeechResult to SPEECH (speech_event_t) and PEOPLE_AUDIO (people_detections_t).

#include <cmath>
#include <string>

#include "common/options.h"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/speech_event_t.hpp"
#include "speech/speech_processor.h"

namespace sarmap {
namespace speech {

struct SpeechNodeOptions {
  std::string audio_channel = "AUDIO";
  std::string doa_channel = "DOA";
  std::string speech_channel = "SPEECH";
  std::string people_channel = "PEOPLE_AUDIO";
  std::string array = "config/arrays/respeaker4.yaml";
  std::string device_id = "";
  double max_bridged_gap_s = 0.25;  // longest audio gap counted as bridged, not a restart
  std::string search = "auto";  // must match the localiser's (1d for linear arrays)
  SpeechOptions speech;
  template <class V>
  void Visit(V& v) {
    v("audio_channel", audio_channel, "input audio_frame_t");
    v("doa_channel", doa_channel, "input doa_t (tracked directions)");
    v("speech_channel", speech_channel, "output speech_event_t");
    v("people_channel", people_channel, "output people_detections_t (CUE_HEARD)");
    v("array", array, "array description (config/arrays/<name>.yaml)");
    v("device_id", device_id,
      "only this device ('' = the first heard); others are dropped and reported");
    v("max_bridged_gap_s", max_bridged_gap_s,
      "an audio gap up to this long is counted as bridged, a longer one as a restart",
      NonNegative());
    v("search", search, "direction kind of the DOA input: auto, 1d, azimuth, azimuth_elevation (as the localiser's "
      "localiser.search; 1d for linear arrays)");
    v("speech", speech, "enhancement, VAD and keyword spotting");
  }
};

inline speech_event_t ToSpeechEvent(const SpeechResult& r, int64_t start_utime, int64_t end_utime) {
  speech_event_t e;
  e.header.utime = start_utime;
  e.header.frame = "mic_array";
  e.track_id = r.track_id;
  e.text = r.text;
  e.keyword = r.keyword;
  e.confidence = static_cast<float>(r.confidence);
  e.azimuth_rad = r.has_direction ? r.direction.azimuth_rad : NAN;
  e.elevation_rad = r.has_direction ? r.direction.elevation_rad : NAN;
  e.start_utime = start_utime;
  e.end_utime = end_utime;
  e.is_final = true;
  return e;
}

// A heard person: the direction only (no range), with the keyword. r must have a direction.
inline people_detections_t ToPeopleAudio(const SpeechResult& r, const std::string& device,
                                         int64_t utime) {
  people_detections_t d;
  d.header.utime = utime;
  d.header.frame = "mic_array";
  d.sensor_id = device;
  person_detection_t person{};
  person.track_id = r.track_id;
  person.cue = person_detection_t::CUE_HEARD;
  person.has_range = false;
  for (double& v : person.position_m) v = 0;
  for (double& v : person.position_covariance) v = 0;
  person.azimuth_rad = r.direction.azimuth_rad;
  person.elevation_rad = r.direction.elevation_rad;
  for (int i = 0; i < 4; ++i) person.direction_covariance[i] = r.covariance(i / 2, i % 2);
  person.height_m = 0;
  person.confidence = static_cast<float>(r.confidence);
  person.keyword = r.keyword;
  d.detections.push_back(person);
  d.num_detections = 1;
  return d;
}

}  // namespace speech
}  // namespace sarmap
