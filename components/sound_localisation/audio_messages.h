#pragma once
// audio_frame_t -> what the audio intake checks (adapters only: the core has no message types).

#include "sarmap/audio_frame_t.hpp"
#include "sound_localisation/audio_intake.h"

namespace sarmap {
namespace sound {

inline AudioBlockFormat AudioBlockFormatOf(const audio_frame_t& m) {
  AudioBlockFormat f;
  f.device_id = m.device_id;
  f.sample_rate_hz = m.sample_rate_hz;
  f.num_channels = m.num_channels;
  f.num_samples = m.num_samples;
  f.num_values = m.num_values;
  f.int16 = m.sample_format == audio_frame_t::SAMPLE_INT16;
  return f;
}

}  // namespace sound
}  // namespace sarmap
