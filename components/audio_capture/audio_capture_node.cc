#include "audio_capture/audio_capture_node.h"

#include <algorithm>
#include <cmath>

#include "common/logging.h"
#include "common/options.h"

namespace sarmap {
namespace audio {
namespace {

std::unique_ptr<AudioSource> Open(const CaptureOptions& options) {
  try {
    return OpenAudioSource(options);
  } catch (const AudioSourceError& e) {
    throw common::OptionsError(e.what());  // one clear line, exit code 2
  }
}

}  // namespace

AudioCaptureNode::AudioCaptureNode(const CaptureOptions& options, common::Node* node)
    : source_(Open(options)),
      node_(node),
      channel_(OutputChannel(options.channel, source_->device_id())),
      pub_(node->Advertise<audio_frame_t>(channel_)),
      checker_(options, source_->sample_rate_hz(), source_->num_channels()),
      frames_per_block_(
          std::max(1, static_cast<int>(std::lround(options.block_s * source_->sample_rate_hz())))) {
  SARMAP_LOG(INFO) << "capturing '" << source_->device_id() << "' (" << source_->num_channels()
                   << " ch, " << source_->sample_rate_hz() << " Hz) -> " << channel_;
  // Every spin reads a block: the source paces the loop (a device's clock, a file's speed).
  node->AddTimer(0.0, [this] {
    if (!Step()) node_->Stop();
  });
}

bool AudioCaptureNode::Step() {
  if (!source_->Read(frames_per_block_, &block_)) {
    SARMAP_LOG(INFO) << "end of stream after " << published_ << " blocks";
    return false;
  }
  for (const auto& w : checker_.Check(block_))
    SARMAP_LOG(WARN) << source_->device_id() << ": " << w;
  if (block_.overrun_samples != last_overrun_) {
    SARMAP_LOG(WARN) << source_->device_id() << ": " << (block_.overrun_samples - last_overrun_)
                     << " samples lost before sample " << block_.first_sample_index;
    last_overrun_ = block_.overrun_samples;
  }
  audio_frame_t msg{};
  msg.header.utime = block_.utime;
  msg.header.frame = "mic_array";
  msg.device_id = source_->device_id();
  msg.sample_rate_hz = source_->sample_rate_hz();
  msg.num_channels = static_cast<int16_t>(block_.num_channels);
  msg.num_samples = block_.num_frames;
  msg.first_sample_index = block_.first_sample_index;
  msg.overrun_samples = block_.overrun_samples;
  msg.sample_format = audio_frame_t::SAMPLE_INT16;
  msg.num_values = static_cast<int32_t>(block_.samples.size());
  msg.samples = block_.samples;
  pub_.Publish(&msg);
  ++published_;
  node_->SetStatusMessage("blocks " + std::to_string(published_) + ", lost samples " +
                          std::to_string(block_.overrun_samples) + ", clipped samples " +
                          std::to_string(checker_.clipped_samples()));
  return true;
}

}  // namespace audio
}  // namespace sarmap
