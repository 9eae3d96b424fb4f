#include "sound_localisation/sound_localisation_node.h"

#include <algorithm>
#include <stdexcept>

#include "common/options.h"
#include "common/robot_config.h"
#include "sound_localisation/audio_messages.h"

namespace sarmap {
namespace sound {
namespace {

std::unique_ptr<DoaStream> MakeStream(const SoundLocalisationOptions& options,
                                      const common::MicArrayOptions& array) {
  const std::string array_dir = options.array.substr(0, options.array.find_last_of('/') + 1);
  try {
    return std::make_unique<DoaStream>(options, array, array_dir);
  } catch (const std::invalid_argument& e) {
    throw common::OptionsError(e.what());
  }
}

}  // namespace

SoundLocalisationNode::SoundLocalisationNode(const SoundLocalisationOptions& options,
                                             common::Node* node)
    : options_(options),
      node_(node),
      array_(common::LoadMicArray(options.array)),
      stream_(MakeStream(options, array_)),
      pub_(node->Advertise<doa_t>(options.doa_channel)),
      intake_(options.device_id, stream_->geometry().sample_rate_hz, options.max_bridged_gap_s),
      device_(options.device_id) {
  const ArrayGeometry& geometry = stream_->geometry();
  for (int c : geometry.channel_map) needed_channels_ = std::max(needed_channels_, c + 1);
  if (stream_->has_map_stream())
    map_pub_.push_back(node->Advertise<doa_t>(options_.map_doa_channel));

  if (!options_.devices.empty()) {
    if (static_cast<int>(options_.mic_devices.size()) != geometry.num_mics()) {
      throw common::OptionsError("mic_devices has " + std::to_string(options_.mic_devices.size()) +
                                 " entries, array '" + geometry.name + "' has " +
                                 std::to_string(geometry.num_mics()) + " microphones");
    }
    try {
      aligner_ = std::make_unique<AsyncStreamAligner>(
          geometry.sample_rate_hz, array_.start_offsets_s, array_.clock_drift, geometry.num_mics());
    } catch (const std::invalid_argument& e) {
      throw common::OptionsError(e.what());
    }
    needed_per_device_.assign(options_.devices.size(), 0);
    device_expected_.assign(options_.devices.size(), -1);
    for (int m = 0; m < geometry.num_mics(); ++m) {
      int& needed = needed_per_device_[options_.mic_devices[m]];
      needed = std::max(needed, geometry.channel_map[m] + 1);
    }
    device_.clear();
    for (const auto& d : options_.devices) device_ += (device_.empty() ? "" : "+") + d;
    stream_->set_device(device_);
    std::vector<std::string> channels = options_.audio_channels;
    if (channels.empty()) channels.push_back(options_.audio_channel);
    for (const auto& ch : channels) {
      node->Subscribe<audio_frame_t>(
          ch, [this](const audio_frame_t& m, const common::ReceiveInfo&) { OnAsyncAudio(m); });
    }
  } else {
    node->Subscribe<audio_frame_t>(
        options_.audio_channel,
        [this](const audio_frame_t& m, const common::ReceiveInfo&) { OnAudio(m); });
  }
  SARMAP_LOG(INFO) << "localising array '" << geometry.name << "' (" << geometry.num_mics()
                   << " mics, " << options_.localiser.method << ") from " << options_.audio_channel
                   << " -> " << options_.doa_channel
                   << (stream_->has_map_stream()
                           ? " and " + options_.map_doa_channel + " (map_localiser)"
                           : "");
}

void SoundLocalisationNode::Drop(const std::string& why) {
  ++dropped_;
  long suppressed = 0;
  if (warn_limit_.Allow(common::SteadySeconds(), &suppressed)) {
    SARMAP_LOG(WARN) << why
                     << (suppressed ? " (" + std::to_string(suppressed) + " similar suppressed)"
                                    : "");
  }
  UpdateStatus();
}

void SoundLocalisationNode::Publish() {
  for (auto& d : doas_) pub_.Publish(&d);
  for (auto& d : map_doas_) map_pub_[0].Publish(&d);
  published_ += static_cast<int64_t>(doas_.size() + map_doas_.size());
  doas_.clear();
  map_doas_.clear();
}

void SoundLocalisationNode::UpdateStatus() {
  if (aligner_) {
    node_->SetStatusMessage("doa " + std::to_string(published_) + ", dropped audio blocks " +
                            std::to_string(dropped_) + ", samples lost " +
                            std::to_string(aligner_->dropped_samples()));
  } else {
    node_->SetStatusMessage("doa " + std::to_string(published_) + ", dropped audio blocks " +
                            std::to_string(dropped_) + "; audio " + intake_.Summary());
  }
}

void SoundLocalisationNode::OnAudio(const audio_frame_t& msg) {
  if (!intake_.FromDeviceLogged(msg.device_id)) {
    ++dropped_;
    UpdateStatus();
    return;
  }
  device_ = intake_.device();
  stream_->set_device(device_);
  const ArrayGeometry& geometry = stream_->geometry();
  const std::string bad = CheckAudioBlock(AudioBlockFormatOf(msg), geometry.sample_rate_hz,
                                          needed_channels_, geometry.name);
  if (!bad.empty()) return Drop(bad);
  if (msg.overrun_samples != last_overrun_) {
    if (warn_limit_.Allow(common::SteadySeconds())) {
      SARMAP_LOG(WARN) << "device '" << common::EscapeForLog(device_) << "' lost "
                       << (msg.overrun_samples - last_overrun_) << " samples (overrun)";
    }
    last_overrun_ = msg.overrun_samples;
  }
  const AudioIntake::Decision decision = intake_.Sequence(msg.first_sample_index, msg.num_samples);
  switch (decision.verdict) {
    case AudioIntake::Verdict::kStale:
      return Drop("audio block at sample " + std::to_string(msg.first_sample_index) +
                  " repeats or precedes what was analysed; dropped");
    case AudioIntake::Verdict::kBridge:
      // A lost datagram or a few: go on, the time line advanced by the gap.
      stream_->SkipSamples(decision.gap_samples);
      break;
    case AudioIntake::Verdict::kRestart:
      if (warn_limit_.Allow(common::SteadySeconds())) {
        SARMAP_LOG(WARN) << "audio discontinuity of " << decision.gap_samples
                         << " samples at sample " << msg.first_sample_index
                         << "; restarting the analysis";
      }
      stream_->ResetStream();
      break;
    default:
      break;
  }
  stream_->Push(msg.samples.data(), msg.num_samples, msg.num_channels, msg.header.utime, &doas_,
                &map_doas_);
  Publish();
  UpdateStatus();
}

void SoundLocalisationNode::OnAsyncAudio(const audio_frame_t& msg) {
  const auto it = std::find(options_.devices.begin(), options_.devices.end(), msg.device_id);
  if (it == options_.devices.end()) {
    return Drop("audio from device '" + common::EscapeForLog(msg.device_id, 64) +
                "' ignored: not one of this array's devices");
  }
  const int d = static_cast<int>(it - options_.devices.begin());
  const ArrayGeometry& geometry = stream_->geometry();
  const std::string bad = CheckAudioBlock(AudioBlockFormatOf(msg), geometry.sample_rate_hz,
                                          needed_per_device_[d], geometry.name);
  if (!bad.empty()) return Drop(bad);
  // Rate-limited: at datagram loss every lost block is a gap (the aligner counts them all).
  if (device_expected_[d] >= 0 && msg.first_sample_index != device_expected_[d] &&
      warn_limit_.Allow(common::SteadySeconds())) {
    SARMAP_LOG(WARN) << "device '" << common::EscapeForLog(msg.device_id)
                     << "': gap, expected sample " << device_expected_[d] << ", got "
                     << msg.first_sample_index << " (filled with zeros)";
  }
  device_expected_[d] = msg.first_sample_index + msg.num_samples;
  for (int m = 0; m < geometry.num_mics(); ++m) {
    if (options_.mic_devices[m] != d) continue;
    channel_.resize(msg.num_samples);
    for (int i = 0; i < msg.num_samples; ++i)
      channel_[i] = msg.samples[i * msg.num_channels + geometry.channel_map[m]] / 32768.0f;
    aligner_->Push(m, msg.first_sample_index, channel_.data(), channel_.size());
  }
  if (d == options_.mic_devices[0]) {
    ref_utime_ = msg.header.utime;
    ref_first_ = msg.first_sample_index;
  }
  for (auto& a : aligned_) a.clear();
  const int64_t first = aligner_->next_reference_sample();
  const size_t n = aligner_->Pull(&aligned_);
  if (n == 0) return;
  const int64_t before = stream_->samples_seen();
  // Stream sample `before` is reference sample `first`.
  stream_->PushFloat(aligned_, n, ref_utime_, before + (ref_first_ - first), &doas_, &map_doas_);
  Publish();
  UpdateStatus();
}

}  // namespace sound
}  // namespace sarmap
