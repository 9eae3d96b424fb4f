#pragma once
// SpeechNode: the LCM adapter of the speech chain. AUDIO + DOA in; SPEECH (speech_event_t) and
// PEOPLE_AUDIO (people_detections_t) out: per tracked source an MVDR beam with post-filter,
// voice activity, PocketSphinx keywords (SpeechStream). Audio blocks of another device, of the
// wrong sample rate or channel count, malformed, repeated or late are dropped and counted.

#include <memory>
#include <string>
#include <vector>

#include "common/logging.h"
#include "common/node.h"
#include "sound_localisation/audio_intake.h"
#include "speech/speech_messages.h"
#include "speech/speech_stream.h"

namespace sarmap {
namespace speech {

class SpeechNode {
 public:
  // Throws common::OptionsError on an unusable array or options.
  SpeechNode(const SpeechNodeOptions& options, common::Node* node);

  // At the end (SIGINT/SIGTERM, or the end of a replayed log): publishes the utterances still
  // open.
  void Finish();

  int64_t dropped() const { return dropped_; }
  int64_t events() const { return events_; }
  int64_t people() const { return people_; }
  const SpeechStream& stream() const { return *stream_; }

 private:
  void OnDoa(const doa_t& msg);
  void OnAudio(const audio_frame_t& msg);
  void Publish();
  void Drop(const std::string& why);
  void UpdateStatus();

  SpeechNodeOptions options_;
  common::Node* node_;
  std::unique_ptr<SpeechStream> stream_;
  int needed_channels_ = 0;
  common::Node::Publisher<speech_event_t> speech_pub_;
  common::Node::Publisher<people_detections_t> people_pub_;
  sound::AudioIntake intake_;
  std::string device_;
  int64_t dropped_ = 0, events_ = 0, people_ = 0;
  common::RateLimiter warn_limit_{5.0};
  std::vector<std::string> warnings_;
  std::vector<speech_event_t> event_msgs_;
  std::vector<people_detections_t> people_msgs_;
};

}  // namespace speech
}  // namespace sarmap
