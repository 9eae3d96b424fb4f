#pragma once
// The microphone array: every source's signal is convolved with the room impulse response
// from the source to each microphone (image-source method, recomputed when the array has
// moved more than a few centimetres), plus the robot's motor noise, diffuse ambient noise and
// each microphone's self noise, then quantised to int16.
//
// Synchronous array: one device, all channels sampled together (channel AUDIO).
// Asynchronous array: each microphone is its own sound card i with start offset tau_i and
// clock drift delta_i (from the array file): its sample k is taken at true time
//   t_i(k) = tau_i + k / (fs (1 + delta_i)),
// read from the true-time signal by windowed-sinc interpolation (channel AUDIO_<DEVICE>).

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "common/robot_config.h"
#include "common/transform.h"
#include "sarmap/audio_frame_t.hpp"
#include "sim/acoustics.h"
#include "sim/sim_options.h"
#include "sim/sound_sources.h"
#include "sim/world.h"

namespace sarmap {
namespace sim {

struct AudioFrameOut {
  std::string channel_suffix;  // "" for the synchronous array, else the device name
  sarmap::audio_frame_t frame;
};

class AudioSim {
 public:
  AudioSim(const AudioOptions& options, const common::MicArrayOptions& array,
           const common::Rigid3d& base_from_array, const World& world,
           std::vector<std::unique_ptr<SourceSignal>> signals, uint64_t seed);
  ~AudioSim();

  int sample_rate_hz() const { return rate_; }
  // Samples of true-time signal generated so far.
  int64_t generated() const { return generated_; }
  // Generates the next block of true-time pressure at every microphone, with the robot at
  // map_from_base moving at speed_mps / turn_radps (motor noise).
  void GenerateBlock(const common::Rigid2d& map_from_base, double speed_mps, double turn_radps);
  // Appends every complete frame whose samples lie before true time `t_s`.
  void CollectFrames(double t_s, int64_t start_utime, std::vector<AudioFrameOut>* frames);
  // The true-time pressure signal (Pa) at microphone m since sample `first` (tests).
  const std::vector<float>& history(int mic) const { return history_[mic]; }
  int64_t history_start() const { return history_start_; }
  void set_keep_history(bool keep) { keep_all_history_ = keep; }
  const std::vector<SourceSignal*> signals() const;
  std::vector<std::string> device_names() const;
  int rir_updates() const { return rir_updates_; }

 private:
  struct Source;
  struct Device;
  float Read(int mic, double sample_pos) const;

  AudioOptions options_;
  common::MicArrayOptions array_;
  common::Rigid3d base_from_array_;
  int rate_;
  int mics_;
  double pa_to_counts_;
  ShoeboxRoom room_;
  RirOptions rir_options_;
  std::vector<std::unique_ptr<Source>> sources_;
  std::vector<std::vector<float>> motor_fir_;
  std::vector<float> motor_state_;
  double motor_lowpass_ = 0, motor_phase_ = 0;
  double ambient_pa_, sensor_pa_, motor_pa_;
  std::vector<double> ambient_lowpass_;
  std::vector<std::vector<float>> history_;
  int64_t history_start_ = 0;
  bool keep_all_history_ = false;
  int64_t generated_ = 0;
  std::vector<Device> devices_;
  std::vector<float> sinc_table_;  // windowed-sinc kernel at kPhases fractional phases
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  int rir_updates_ = 0;
};

}  // namespace sim
}  // namespace sarmap
