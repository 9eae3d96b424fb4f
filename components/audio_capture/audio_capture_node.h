#pragma once
// AudioCaptureNode: the LCM adapter of audio capture. An ALSA device or a multichannel audio
// file -> audio_frame_t on AUDIO (or AUDIO_<DEVICE>). One process per sound card: each has its
// own clock and sample counter. The node reads a block whenever it spins, and stops at the end
// of a file.

#include <memory>
#include <string>

#include "audio_capture/audio_source.h"
#include "common/node.h"
#include "sarmap/audio_frame_t.hpp"

namespace sarmap {
namespace audio {

class AudioCaptureNode {
 public:
  // Throws common::OptionsError when the device or file cannot be opened.
  AudioCaptureNode(const CaptureOptions& options, common::Node* node);

  // Reads and publishes one block; false at the end of the stream (the node is stopped).
  bool Step();
  int64_t published() const { return published_; }

 private:
  std::unique_ptr<AudioSource> source_;
  common::Node* node_;
  std::string channel_;
  common::Node::Publisher<audio_frame_t> pub_;
  SignalChecker checker_;
  int frames_per_block_;
  AudioBlock block_;
  int64_t published_ = 0, last_overrun_ = 0;
};

}  // namespace audio
}  // namespace sarmap
