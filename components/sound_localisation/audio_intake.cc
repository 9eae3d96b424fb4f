#include "sound_localisation/audio_intake.h"

#include <cmath>
#include <stdexcept>

#include "common/logging.h"

namespace sarmap {
namespace sound {

std::string CheckAudioBlock(const AudioBlockFormat& block, int array_rate_hz, int needed_channels,
                            const std::string& array_name) {
  const std::string device = "device '" + common::EscapeForLog(block.device_id, 64) + "'";
  if (block.sample_rate_hz != array_rate_hz) {
    return "sample-rate mismatch: " + device + " is " + std::to_string(block.sample_rate_hz) +
           " Hz, array '" + array_name + "' expects " + std::to_string(array_rate_hz) +
           " Hz; block dropped";
  }
  if (block.num_channels < needed_channels) {
    return device + " has " + std::to_string(block.num_channels) + " channels, array '" +
           array_name + "' needs " + std::to_string(needed_channels) +
           " (channel_map); block dropped";
  }
  if (!block.int16 || block.num_samples < 0 ||
      block.num_values != static_cast<int64_t>(block.num_channels) * block.num_samples) {
    return "malformed audio block of " + device + " (format or size); dropped";
  }
  return "";
}

AudioIntake::AudioIntake(std::string device_id, int sample_rate_hz, double max_bridged_gap_s)
    : device_(std::move(device_id)), configured_(!device_.empty()) {
  if (sample_rate_hz <= 0) throw std::invalid_argument("audio intake: sample rate must be > 0");
  if (!(max_bridged_gap_s >= 0)) {
    throw std::invalid_argument("audio intake: max_bridged_gap_s must be >= 0");
  }
  max_bridged_samples_ = static_cast<int64_t>(std::llround(max_bridged_gap_s * sample_rate_hz));
}

bool AudioIntake::FromDeviceLogged(const std::string& device_id) {
  std::string report;
  const bool ours = FromDevice(device_id, &report);
  if (!report.empty()) {
    if (ours) {
      SARMAP_LOG(INFO) << common::EscapeForLog(report, 512);
    } else {
      SARMAP_LOG(ERROR) << common::EscapeForLog(report, 512);
    }
  }
  return ours;
}

bool AudioIntake::FromDevice(const std::string& device_id, std::string* report) {
  report->clear();
  if (device_.empty()) {
    device_ = device_id;
    *report = "analysing audio device '" + device_ + "', the first heard (set device_id to " +
              "choose it; every other device is then dropped and reported)";
  }
  if (device_id == device_) return true;
  ++other_device_blocks_;
  if (others_.count(device_id) == 0) {
    if (others_.size() < kMaxNamedDevices) {
      others_.insert(device_id);
      *report = "a second audio device '" + device_id + "' on the channel: its blocks are " +
                "dropped, this node analyses '" + device_ + "'" +
                (configured_ ? " (device_id)" : " (the first heard; set device_id to choose)") +
                "; counted in NODE_STATUS";
    } else if (!others_overflowed_) {
      others_overflowed_ = true;
      *report = "more than " + std::to_string(kMaxNamedDevices) +
                " other audio devices on the channel: further ones only counted";
    }
  }
  return false;
}

AudioIntake::Decision AudioIntake::Offer(const std::string& device_id, int64_t first_sample_index,
                                         int64_t num_samples) {
  std::string report;
  if (!FromDevice(device_id, &report)) {
    Decision d;
    d.verdict = Verdict::kOtherDevice;
    d.report = report;
    return d;
  }
  Decision d = Sequence(first_sample_index, num_samples);
  if (!report.empty()) d.report = report;
  return d;
}

AudioIntake::Decision AudioIntake::Sequence(int64_t first_sample_index, int64_t num_samples) {
  Decision d;
  // A counter that would overflow cannot be a device's: dropped as stale.
  int64_t end_index = 0, jump = 0;
  if (num_samples < 0 || __builtin_add_overflow(first_sample_index, num_samples, &end_index) ||
      (expected_index_ >= 0 &&
       __builtin_sub_overflow(first_sample_index, expected_index_, &jump))) {
    ++stale_blocks_;
    d.verdict = Verdict::kStale;
    return d;
  }
  if (expected_index_ >= 0) {
    if (jump > 0 && jump <= max_bridged_samples_) {
      d.verdict = Verdict::kBridge;
      d.gap_samples = jump;
      ++bridged_gaps_;
      bridged_samples_ += jump;
    } else if (jump < 0 && jump >= -max_bridged_samples_ - num_samples) {
      // At or behind the analysed stream (a duplicate or a late datagram).
      ++stale_blocks_;
      d.verdict = Verdict::kStale;
      return d;
    } else if (jump != 0) {
      d.verdict = Verdict::kRestart;
      d.gap_samples = jump;
      ++restarts_;
    }
  }
  expected_index_ = end_index;
  ++blocks_;
  return d;
}

std::string AudioIntake::Summary() const {
  return "blocks " + std::to_string(blocks_) + ", bridged gaps " + std::to_string(bridged_gaps_) +
         " (" + std::to_string(bridged_samples_) + " samples), restarts " +
         std::to_string(restarts_) + ", stale " + std::to_string(stale_blocks_) +
         ", other devices " + std::to_string(others_.size()) + (others_overflowed_ ? "+" : "") +
         " (" + std::to_string(other_device_blocks_) + " blocks)";
}

}  // namespace sound
}  // namespace sarmap
