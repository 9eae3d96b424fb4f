#pragma once
// AudioIntake: which audio blocks of one device a node analyses, and how it joins them.
//
// Audio arrives in blocks stamped with a device id and the device's running sample counter
// (audio_frame_t). A node analyses one device (one clock): the configured one, or, with none
// configured, the first it hears. A block from any other device is dropped and counted, and
// the first block of each other device is reported once, naming both, so a second source on
// the channel (a second array, a misconfigured capture, a hostile publisher) is never mixed in
// or locked onto silently.
//
// A lost datagram is a gap in the counter. A gap of up to max_bridged_gap_s is bridged: the
// node goes on with the next block as if contiguous, its time line advanced by the gap (on one
// clock every channel jumps at the same instant, so the inter-channel delays that DOA and
// beams use stay right on both sides of the join). A longer gap, or a counter that goes back
// further than that (the device reopened), is a real discontinuity: the analysis restarts. A
// block at or behind the counter by less than that (a duplicate, a late datagram) is dropped.
#include <cstdint>
#include <set>
#include <string>

namespace sarmap {
namespace sound {

// The format fields of one audio block (audio_frame_t), as a node checks them.
struct AudioBlockFormat {
  std::string device_id;
  int sample_rate_hz = 0;
  int num_channels = 0;
  int64_t num_samples = 0;  // per channel
  int64_t num_values = 0;   // must be num_channels * num_samples
  bool int16 = true;        // SAMPLE_INT16, the only format on the wire
};

// "" when `block` is what an array of `array_name` needs (its sample rate, at least
// `needed_channels` device channels, 16-bit samples, as many values as channels x samples);
// else one line saying why the block is dropped.
std::string CheckAudioBlock(const AudioBlockFormat& block, int array_rate_hz, int needed_channels,
                            const std::string& array_name);

class AudioIntake {
 public:
  // Other device ids remembered to report each once; beyond this they are only counted.
  static constexpr size_t kMaxNamedDevices = 16;

  enum class Verdict {
    kContinue,     // the next block of the stream
    kBridge,       // after a short gap (gap_samples): go on, time line advanced by the gap
    kRestart,      // after a discontinuity: restart the analysis with this block
    kOtherDevice,  // not this node's device: drop
    kStale,        // at or behind what was analysed: drop
  };
  struct Decision {
    Verdict verdict = Verdict::kContinue;
    int64_t gap_samples = 0;  // kBridge, kRestart: counter jump before this block
    std::string report;       // a line to log (first block, first block of another device)
  };

  // `device_id` "": the first device heard. Throws std::invalid_argument for a sample rate
  // <= 0 or a negative max_bridged_gap_s.
  AudioIntake(std::string device_id, int sample_rate_hz, double max_bridged_gap_s);

  // The verdict for a block of `num_samples` starting at the device's `first_sample_index`:
  // FromDevice, then Sequence.
  Decision Offer(const std::string& device_id, int64_t first_sample_index, int64_t num_samples);
  // Whether a block of `device_id` is this node's (the first call picks the device when none
  // is configured); blocks of other devices are counted. *report: a line to log, or "".
  bool FromDevice(const std::string& device_id, std::string* report);
  // FromDevice with its report logged (escaped: a device id is whatever the bus sent): INFO
  // when the block is this node's (the device picked, the others heard), ERROR when not.
  bool FromDeviceLogged(const std::string& device_id);
  // The verdict for the next block of this node's device (nodes check its format in between).
  Decision Sequence(int64_t first_sample_index, int64_t num_samples);

  const std::string& device() const { return device_; }  // "" until the first block
  int64_t blocks() const { return blocks_; }             // accepted (continue, bridge, restart)
  int64_t other_device_blocks() const { return other_device_blocks_; }
  // Distinct other device ids seen (the first kMaxNamedDevices).
  int64_t other_devices() const { return static_cast<int64_t>(others_.size()); }
  int64_t bridged_gaps() const { return bridged_gaps_; }
  int64_t bridged_samples() const { return bridged_samples_; }
  int64_t restarts() const { return restarts_; }
  int64_t stale_blocks() const { return stale_blocks_; }
  // "blocks N, bridged gaps G (S samples), restarts R, stale B, other devices D (B blocks)".
  std::string Summary() const;

 private:
  std::string device_;
  const bool configured_;
  int64_t max_bridged_samples_;
  int64_t expected_index_ = -1;
  std::set<std::string> others_;
  bool others_overflowed_ = false;
  int64_t blocks_ = 0, other_device_blocks_ = 0, bridged_gaps_ = 0, bridged_samples_ = 0,
          restarts_ = 0, stale_blocks_ = 0;
};

}  // namespace sound
}  // namespace sarmap
