#pragma once
// Shoebox rooms for the sound tests and benchmarks: room impulse responses from a point source
// to each microphone, and the microphone signals of several sources plus sensor noise.
//
// The impulse responses come from the simulator's image-source engine (sim/acoustics.h,
// Allen & Berkley 1979), every image placed with a Hann-windowed sinc. Walls reflect with
// pressure coefficient beta = sqrt(1 - alpha), alpha from Sabine's formula
// RT60 = 0.161 V / (S alpha); image (i, j, k) of order |i|+|j|+|k| contributes
// beta^order / (4 pi r) delayed by r / c.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace sarmap {
namespace sound {

struct Room {
  Eigen::Vector3d size_m{6.0, 5.0, 3.0};
  double rt60_s = 0.0;  // 0: anechoic (direct path only)
  double speed_of_sound_mps = 343.0;
  int sample_rate_hz = 16000;
  double max_rir_s = 0.5;  // truncation of the impulse responses
};

// Impulse response (length max_rir_s) from `source` to `mic` (room coordinates).
std::vector<float> RoomImpulseResponse(const Room& room, const Eigen::Vector3d& source,
                                       const Eigen::Vector3d& mic);
// Linear convolution through FFTW; result length x.size() (tail dropped).
std::vector<float> Convolve(const std::vector<float>& x, const std::vector<float>& h);

struct SimSource {
  Eigen::Vector3d position_m;
  std::vector<float> signal;
  double gain = 1.0;
};

// Microphone signals (channel-major) of length `num_samples` for mics at `mic_positions_m`
// (3 x M, room coordinates), with white noise of standard deviation `noise_std` (seeded).
std::vector<std::vector<float>> SimulateRoom(const Room& room,
                                             const Eigen::Matrix3Xd& mic_positions_m,
                                             const std::vector<SimSource>& sources,
                                             size_t num_samples, double noise_std, uint32_t seed);

// What a sound card with its own clock records of a synchronous signal: its sample k is the
// signal at reference sample r = (k - tau fs) / (1 + delta) (async_alignment.h's clock model),
// band-limited by a Hann-windowed sinc of 2 * half_taps taps.
std::vector<float> RecordAsynchronously(const std::vector<float>& sync, double tau_s, double delta,
                                        int fs, int half_taps = 64);

}  // namespace sound
}  // namespace sarmap
