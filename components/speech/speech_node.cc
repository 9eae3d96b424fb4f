#include "speech/speech_node.h"

#include <algorithm>
#include <stdexcept>

#include "common/options.h"
#include "common/robot_config.h"
#include "sound_localisation/audio_messages.h"

namespace sarmap {
namespace speech {
namespace {

std::unique_ptr<SpeechStream> MakeStream(const SpeechNodeOptions& options) {
  const auto array = common::LoadMicArray(options.array);
  try {
    return std::make_unique<SpeechStream>(options, array);
  } catch (const std::invalid_argument& e) {
    throw common::OptionsError(e.what());
  } catch (const std::runtime_error& e) {
    throw common::OptionsError(e.what());
  }
}

}  // namespace

SpeechNode::SpeechNode(const SpeechNodeOptions& options, common::Node* node)
    : options_(options),
      node_(node),
      stream_(MakeStream(options)),
      speech_pub_(node->Advertise<speech_event_t>(options.speech_channel)),
      people_pub_(node->Advertise<people_detections_t>(options.people_channel)),
      intake_(options.device_id, stream_->geometry().sample_rate_hz, options.max_bridged_gap_s),
      device_(options.device_id) {
  for (int c : stream_->geometry().channel_map)
    needed_channels_ = std::max(needed_channels_, c + 1);
  node->Subscribe<doa_t>(options_.doa_channel,
                         [this](const doa_t& m, const common::ReceiveInfo&) { OnDoa(m); });
  node->Subscribe<audio_frame_t>(
      options_.audio_channel,
      [this](const audio_frame_t& m, const common::ReceiveInfo&) { OnAudio(m); });
  SARMAP_LOG(INFO) << "listening to array '" << stream_->geometry().name << "' on "
                   << options_.audio_channel << " + " << options_.doa_channel;
}

void SpeechNode::Drop(const std::string& why) {
  ++dropped_;
  if (warn_limit_.Allow(common::SteadySeconds())) SARMAP_LOG(WARN) << why;
  UpdateStatus();
}

void SpeechNode::OnDoa(const doa_t& msg) {
  warnings_.clear();
  stream_->OnDoa(msg, device_, &warnings_);
  for (const auto& w : warnings_) Drop(w);
}

void SpeechNode::OnAudio(const audio_frame_t& msg) {
  if (!intake_.FromDeviceLogged(msg.device_id)) {
    ++dropped_;
    UpdateStatus();
    return;
  }
  device_ = intake_.device();
  const sound::ArrayGeometry& geometry = stream_->geometry();
  const std::string bad = sound::CheckAudioBlock(
      sound::AudioBlockFormatOf(msg), geometry.sample_rate_hz, needed_channels_, geometry.name);
  if (!bad.empty()) return Drop(bad);
  // The beams and keyword spotting go on across gaps (each block's stamp anchors its samples);
  // a repeated or late block is dropped.
  const sound::AudioIntake::Decision decision =
      intake_.Sequence(msg.first_sample_index, msg.num_samples);
  if (decision.verdict == sound::AudioIntake::Verdict::kStale) {
    return Drop("audio block at sample " + std::to_string(msg.first_sample_index) +
                " repeats or precedes what was processed; dropped");
  }
  if (decision.verdict == sound::AudioIntake::Verdict::kRestart &&
      warn_limit_.Allow(common::SteadySeconds())) {
    SARMAP_LOG(WARN) << "audio discontinuity of " << decision.gap_samples << " samples";
  }
  event_msgs_.clear();
  people_msgs_.clear();
  stream_->OnAudio(msg.samples.data(), msg.num_samples, msg.num_channels, msg.header.utime, device_,
                   &event_msgs_, &people_msgs_);
  Publish();
}

void SpeechNode::Finish() {
  event_msgs_.clear();
  people_msgs_.clear();
  stream_->Flush(device_, &event_msgs_, &people_msgs_);
  Publish();
}

void SpeechNode::Publish() {
  for (const auto& r : stream_->last_results()) {
    SARMAP_LOG(INFO) << "heard" << (r.keyword.empty() ? "" : " keyword '" + r.keyword + "'")
                     << (r.text.empty() ? "" : " \"" + r.text + "\"") << " track " << r.track_id
                     << " conf " << r.confidence;
  }
  for (auto& e : event_msgs_) speech_pub_.Publish(&e);
  for (auto& d : people_msgs_) people_pub_.Publish(&d);
  events_ += static_cast<int64_t>(event_msgs_.size());
  people_ += static_cast<int64_t>(people_msgs_.size());
  UpdateStatus();
}

void SpeechNode::UpdateStatus() {
  const SpeechProcessor& p = stream_->processor();
  node_->SetStatusMessage(
      "utterances " + std::to_string(p.utterances()) + ", events " + std::to_string(events_) +
      ", people " + std::to_string(people_) + ", dropped " + std::to_string(dropped_) +
      ", leaked hits " + std::to_string(p.leaked_hits_dropped()) + ", re-attributed " +
      std::to_string(p.hits_reattributed()) + ", tracks " + std::to_string(p.num_tracks()) +
      " (evicted " + std::to_string(p.tracks_evicted()) + "); audio " + intake_.Summary());
}

}  // namespace speech
}  // namespace sarmap
