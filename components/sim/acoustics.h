#pragma once
// Room acoustics for the simulated microphone array.
//
// Propagation: a source at distance r reaches a microphone after r / c seconds with pressure
// gain 1/r (spherical spreading). Fractional delays use a Hann-windowed sinc:
//   h[n] += g * sinc(n - D) * w(n - D),  w(x) = 0.5 (1 + cos(pi x / (L + 1))), |n - D| <= L
// Reverberation: the image-source method (Allen & Berkley 1979) for a shoebox room. The image
// of the source for indices (n, l, m) and parities (p, q, r) lies at
//   x = (1 - 2p) xs + 2 n Lx (room-relative), likewise y, z,
// and arrives with gain prod(beta_wall^(number of reflections off that wall)) / distance,
// beta = sqrt(1 - alpha) for energy absorption alpha.
// Absorption from a wanted RT60 (uniform over all surfaces), Eyring:
//   RT60 = 0.161 V / (-S ln(1 - alpha))   =>  alpha = 1 - exp(-0.161 V / (S RT60))
// (Sabine: RT60 = 0.161 V / (S alpha), good for small alpha.)

#include <Eigen/Core>

#include <array>
#include <complex>
#include <memory>
#include <vector>

namespace sarmap {
namespace sim {

struct ShoeboxRoom {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Ones();
  // Pressure reflection coefficients of x-, x+, y-, y+, floor, ceiling.
  std::array<double, 6> beta{{0, 0, 0, 0, 0, 0}};
  double Volume() const { return (max - min).prod(); }
  double Surface() const {
    const Eigen::Vector3d d = max - min;
    return 2 * (d.x() * d.y() + d.x() * d.z() + d.y() * d.z());
  }
};

double EyringAbsorptionForRt60(double volume_m3, double surface_m2, double rt60_s);
double SabineAbsorptionForRt60(double volume_m3, double surface_m2, double rt60_s);
double EyringRt60(double volume_m3, double surface_m2, double absorption);
// Sets all six walls to one absorption so that the image-source impulse response decays
// with rt60_s. Starts from Eyring's formula; because a purely specular shoebox is not a
// diffuse field (the late decay is carried by the few paths that graze the long axis and
// decays slower than Eyring predicts, by 50-80 % in a flat 8 x 6 x 2.7 m room), the
// absorption is then refined on the simulated response: a few image-source evaluations for
// a reference source/mic pair, scaling ln(1 - alpha) by measured T20 / wanted RT60 each time.
// Returns the measured T20 of the last evaluation.
double SetUniformRt60(ShoeboxRoom* room, double rt60_s, double sample_rate_hz = 16000,
                      double speed_of_sound_mps = 343);
void SetAbsorption(ShoeboxRoom* room, const std::vector<double>& absorption);  // 1 or 6 values

// Adds gain * (windowed sinc delayed by delay_samples) to h (grown as needed).
void AddFractionalDelay(std::vector<float>* h, double delay_samples, double gain, int half_width);

struct RirOptions {
  double sample_rate_hz = 16000;
  double speed_of_sound_mps = 343;
  double max_length_s = 0.5;  // images farther than c * max_length_s are dropped
  int exact_order = 2;        // reflections up to this order: windowed sinc; later: linear
  int sinc_half_width = 16;
  bool reverb = true;         // false: direct path only (free field)
  // Which images to include, by reflection order (e.g. only the early part, or only the late
  // part, so a moving array can refresh the early part often and the diffuse tail rarely).
  int min_order = 0;
  int max_order = 1 << 20;
};

// Impulse response from `source` to `mic` (time 0 = emission), pressure per unit source
// pressure at 1 m.
std::vector<float> ImageSourceRir(const ShoeboxRoom& room, const Eigen::Vector3d& source,
                                  const Eigen::Vector3d& mic, const RirOptions& options);

// Reverberation time from an impulse response by Schroeder backward integration, fitting a
// line to the energy decay curve between from_db and to_db (e.g. -5 and -25: T20) and
// extrapolating to -60 dB. Returns <= 0 when the decay never reaches to_db.
double SchroederRt60(const std::vector<float>& h, double sample_rate_hz, double from_db = -5,
                     double to_db = -25);

// One-partition overlap-add FFT convolution of one input with
// several filters (one per microphone), block by block, crossfading when the filters change.
class MultiConvolver {
 public:
  // block: input samples per Process(); max_filter: longest filter.
  MultiConvolver(int block, int max_filter, int outputs);
  ~MultiConvolver();
  MultiConvolver(const MultiConvolver&) = delete;
  MultiConvolver& operator=(const MultiConvolver&) = delete;
  int block() const { return block_; }
  int max_filter() const { return max_filter_; }
  // New filters (outputs of them, each <= max_filter long), used from the next block with a
  // crossfade from the old ones over that block.
  void SetFilters(const std::vector<std::vector<float>>& filters);
  bool has_filters() const { return has_filters_; }
  // Convolves `block` input samples; adds `block` output samples per output to out[o].
  void Process(const float* input, const std::vector<float*>& out);
  // True while the filtered tail of past input is still ringing (input may be skipped when
  // silent and this is false).
  bool ringing() const { return ringing_ > 0; }
  void ProcessSilence(const std::vector<float*>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int block_, max_filter_, outputs_;
  bool has_filters_ = false;
  int ringing_ = 0;
};

}  // namespace sim
}  // namespace sarmap
