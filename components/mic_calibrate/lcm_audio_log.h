#pragma once
// Reads a calibration recording from an LCM log in which every sound card publishes its own
// AUDIO_<DEVICE> channel (audio_frame_t with its own running sample counter). Each device's
// blocks are placed by first_sample_index (gaps and overruns become silence), and the devices
// are put on the reference device's time line by the utime of their first sample; what that
// alignment gets wrong is exactly the start offset / drift the calibration estimates.
// Kept out of the core library: this is the only LCM-dependent piece.

#include <string>
#include <vector>

#include "common/pose_history.h"
#include "mic_calibrate/tdoa_extraction.h"

namespace sarmap {
namespace mic_calibrate {

struct LcmAudioLogStats {
  int frames = 0, bad_frames = 0, devices = 0;
  std::vector<std::string> warnings;
};

// Channels whose name starts with `channel_prefix`, in name order; every channel of every
// device becomes one microphone (device order, then channel order). Throws on an unreadable
// log or no audio; bad frames are counted and skipped.
Recording ReadLcmAudioLog(const std::string& path, const std::string& channel_prefix,
                          LcmAudioLogStats* stats);

// The poses on `channel` of an LCM log, in time order: odometry_t (ODOM), pose_t (POSE, e.g.
// map_from_base from SLAM) or sim_truth_t (SIM_TRUTH), recognised by the message's type
// fingerprint. Throws when the channel holds none of them.
std::vector<common::StampedPose> ReadLcmPoses(const std::string& path, const std::string& channel,
                                              LcmAudioLogStats* stats);

// Writes `rec` as an LCM log: one AUDIO_<name> channel per entry of `devices` (each a list of
// recording channels), blocks of `block` samples, utime = start_utime + (channel start +
// first sample / rate) * 1e6. For tests and for turning a WAV into a multi-card log.
void WriteLcmAudioLog(const std::string& path, const Recording& rec,
                      const std::vector<std::vector<int>>& devices, int64_t start_utime,
                      int block);

}  // namespace mic_calibrate
}  // namespace sarmap
