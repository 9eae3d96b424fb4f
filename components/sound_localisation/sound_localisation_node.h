#pragma once
// SoundLocalisationNode: the LCM adapter of sound localisation. AUDIO (audio_frame_t) in; DOA
// (and DOA_MAP with a map localiser) out: directions with covariance and track ids for one
// microphone array (DoaStream). A synchronous array listens to one device (AudioIntake: other
// devices, wrong formats, repeated blocks dropped and counted; short gaps bridged); an
// asynchronous array (`devices`) aligns its cards' streams first (AsyncStreamAligner).

#include <memory>
#include <string>
#include <vector>

#include "common/logging.h"
#include "common/node.h"
#include "common/robot_config.h"
#include "sound_localisation/async_alignment.h"
#include "sound_localisation/audio_intake.h"
#include "sound_localisation/doa_stream.h"

namespace sarmap {
namespace sound {

class SoundLocalisationNode {
 public:
  // Throws common::OptionsError on an unusable array or options.
  SoundLocalisationNode(const SoundLocalisationOptions& options, common::Node* node);

  int64_t dropped() const { return dropped_; }
  int64_t published() const { return published_; }

 private:
  void OnAudio(const audio_frame_t& msg);       // synchronous array
  void OnAsyncAudio(const audio_frame_t& msg);  // asynchronous array
  void Drop(const std::string& why);
  void Publish();
  void UpdateStatus();

  SoundLocalisationOptions options_;
  common::Node* node_;
  common::MicArrayOptions array_;
  std::unique_ptr<DoaStream> stream_;
  int needed_channels_ = 0;
  common::Node::Publisher<doa_t> pub_;
  std::vector<common::Node::Publisher<doa_t>> map_pub_;  // one with a map localiser
  AudioIntake intake_;
  std::string device_;
  int64_t last_overrun_ = 0, dropped_ = 0, published_ = 0;
  common::RateLimiter warn_limit_{5.0};
  std::vector<doa_t> doas_, map_doas_;
  // Asynchronous arrays: each card's block goes to the aligner; aligned reference samples go to
  // the localiser. Reference time: the card of microphone 0 (tau = 0, drift = 0).
  std::unique_ptr<AsyncStreamAligner> aligner_;
  std::vector<int> needed_per_device_;
  std::vector<int64_t> device_expected_;
  std::vector<std::vector<float>> aligned_;
  std::vector<float> channel_;
  int64_t ref_utime_ = 0, ref_first_ = 0;
};

}  // namespace sound
}  // namespace sarmap
