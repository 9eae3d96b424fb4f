#include "sim/audio_sim.h"

#include <gtest/gtest.h>

#include <fftw3.h>

#include <cmath>
#include <complex>

namespace sarmap {
namespace sim {
namespace {

// Lag (samples, fractional) of b relative to a by GCC-PHAT, upsampled 64x by zero-padding
// the cross-spectrum.
double GccPhatLag(const std::vector<double>& a, const std::vector<double>& b) {
  const int n = static_cast<int>(a.size());
  const int up = 64, m = n * up;
  std::vector<std::complex<double>> A(n / 2 + 1), B(n / 2 + 1), R(m / 2 + 1, 0.0);
  std::vector<double> in(a), in_b(b), out(m);
  fftw_plan pa = fftw_plan_dft_r2c_1d(n, in.data(), reinterpret_cast<fftw_complex*>(A.data()), FFTW_ESTIMATE);
  fftw_execute(pa);
  fftw_plan pb = fftw_plan_dft_r2c_1d(n, in_b.data(), reinterpret_cast<fftw_complex*>(B.data()), FFTW_ESTIMATE);
  fftw_execute(pb);
  for (int k = 0; k <= n / 2; ++k) {
    const std::complex<double> c = B[k] * std::conj(A[k]);
    R[k] = std::abs(c) > 0 ? c / std::abs(c) : 0.0;
  }
  fftw_plan pr = fftw_plan_dft_c2r_1d(m, reinterpret_cast<fftw_complex*>(R.data()), out.data(), FFTW_ESTIMATE);
  fftw_execute(pr);
  fftw_destroy_plan(pa);
  fftw_destroy_plan(pb);
  fftw_destroy_plan(pr);
  int best = 0;
  for (int k = 1; k < m; ++k) {
    if (out[k] > out[best]) best = k;
  }
  double lag = best > m / 2 ? best - m : best;
  return lag / up;
}

World NoiseWorld(const Eigen::Vector3d& source, bool reverb) {
  World world;
  SoundSource s;
  s.id = 1;
  s.name = "noise";
  s.kind = SourceKind::kNoise;
  s.position = source;
  s.level_db_spl = 75;
  world.sources.push_back(s);
  world.acoustics.reverb = reverb;
  world.acoustics.room_min = Eigen::Vector3d(-5, -5, 0);
  world.acoustics.room_max = Eigen::Vector3d(5, 5, 3);
  world.acoustics.ambient_noise_db_spl = 20;
  return world;
}

std::unique_ptr<AudioSim> MakeSim(const World& world, const common::MicArrayOptions& array, AudioOptions options) {
  std::vector<std::unique_ptr<SourceSignal>> signals;
  signals.push_back(std::make_unique<SourceSignal>(world.sources[0], std::vector<std::vector<float>>{}, 16000, 9));
  options.motor_noise_db_spl = 0;
  return std::make_unique<AudioSim>(options, array, common::Rigid3d(), world, std::move(signals), 4);
}

// A source's TDOA between two microphones matches the geometry within a quarter sample.
TEST(AudioSimTest, TdoaMatchesGeometryWithinAQuarterSample) {
  common::MicArrayOptions array;
  array.name = "pair";
  array.geometry = "linear";
  array.mic_positions_m = {-0.113, 0, 0, 0.113, 0, 0};  // the Kinect's outer pair
  AudioOptions options;
  options.reverb = false;
  for (double azimuth_deg : {0.0, 25.0, 60.0, 110.0, 160.0}) {
    const double az = azimuth_deg * M_PI / 180;
    const Eigen::Vector3d source(2.5 * std::cos(az), 2.5 * std::sin(az), 0.3);
    const World world = NoiseWorld(source, false);
    auto sim = MakeSim(world, array, options);
    sim->set_keep_history(true);
    for (int b = 0; b < 20; ++b) sim->GenerateBlock(common::Rigid2d(), 0, 0);
    const int n = 8192, start = 4096;
    std::vector<double> a(n), b(n);
    for (int k = 0; k < n; ++k) {
      a[k] = sim->history(0)[start + k];
      b[k] = sim->history(1)[start + k];
    }
    const double measured = GccPhatLag(a, b);
    const double expected = ((source - array.mic_position(1)).norm() - (source - array.mic_position(0)).norm()) /
                            array.speed_of_sound_mps * 16000;
    std::printf("azimuth %5.1f deg: TDOA expected %+.3f samples, measured %+.3f\n", azimuth_deg, expected, measured);
    EXPECT_NEAR(measured, expected, 0.25) << azimuth_deg;
  }
}

TEST(AudioSimTest, ReverberantRoomStillPublishesContinuousSynchronousFrames) {
  common::MicArrayOptions array;
  array.name = "kinect";
  array.mic_positions_m = {-0.113, 0, 0, 0.036, 0, 0, 0.076, 0, 0, 0.113, 0, 0};
  const World world = NoiseWorld({2, 1, 1}, true);
  AudioOptions options;
  auto sim = MakeSim(world, array, options);
  std::vector<AudioFrameOut> frames;
  for (int b = 0; b < 16; ++b) {
    sim->GenerateBlock(common::Rigid2d(0.01 * b, 0, 0), 0.2, 0);  // moving: filters update
    sim->CollectFrames(sim->generated() / 16000.0, 1000000, &frames);
  }
  ASSERT_GE(frames.size(), 30u);
  EXPECT_GT(sim->rir_updates(), 1);
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto& f = frames[k].frame;
    EXPECT_EQ(f.num_channels, 4);
    EXPECT_EQ(f.first_sample_index, static_cast<int64_t>(k) * options.block_samples);
    EXPECT_EQ(f.header.utime, 1000000 + static_cast<int64_t>(std::llround(f.first_sample_index / 16.0 * 1000)));
    EXPECT_EQ(static_cast<int>(f.samples.size()), f.num_values);
  }
  double energy = 0;
  for (int16_t v : frames.back().frame.samples) energy += static_cast<double>(v) * v;
  EXPECT_GT(energy / frames.back().frame.samples.size(), 100.0);  // the source is audible
}

// Two sound cards with start offsets and drift hear the same microphone position: the offset
// between their streams grows by fs * (delta_1 - delta_0) samples per second.
TEST(AudioSimTest, ClockDriftShowsAsAGrowingOffset) {
  common::MicArrayOptions array;
  array.name = "usb";
  array.mic_positions_m = {0, 0, 0, 0, 0, 0};
  array.start_offsets_s = {0.0, 0.01};
  array.clock_drift = {0.0, 4e-4};
  AudioOptions options;
  options.reverb = false;
  options.asynchronous = true;
  const World world = NoiseWorld({1.5, 0.5, 0.2}, false);
  auto sim = MakeSim(world, array, options);
  std::vector<AudioFrameOut> frames;
  while (sim->generated() < 16000 * 4) {
    sim->GenerateBlock(common::Rigid2d(), 0, 0);
    sim->CollectFrames(sim->generated() / 16000.0, 0, &frames);
  }
  std::vector<double> dev[2];
  for (const auto& f : frames) {
    const int d = f.channel_suffix == "USB0" ? 0 : f.channel_suffix == "USB1" ? 1 : -1;
    ASSERT_GE(d, 0) << f.channel_suffix;
    EXPECT_EQ(f.frame.first_sample_index, static_cast<int64_t>(dev[d].size()));
    for (int16_t v : f.frame.samples) dev[d].push_back(v);
  }
  const double fs = 16000, tau = 0.01, delta = 4e-4;
  double previous = 0;
  for (double t : {0.6, 1.6, 2.6}) {
    // Device 0 sample j = t fs is heard by device 1 at k = (t - tau) fs (1 + delta).
    const int n = 4096;
    const int j0 = static_cast<int>(t * fs) - n / 2;
    const double k_expected = (t - tau) * fs * (1 + delta);
    const int k0 = static_cast<int>(std::lround(k_expected)) - n / 2;
    ASSERT_LT(j0 + n, static_cast<int>(dev[0].size()));
    ASSERT_LT(k0 + n, static_cast<int>(dev[1].size()));
    std::vector<double> a(dev[0].begin() + j0, dev[0].begin() + j0 + n), b(dev[1].begin() + k0, dev[1].begin() + k0 + n);
    // b[i] holds device-1 sample k0 + i; the event at a[n/2] appears at b[n/2 + lag].
    const double lag = GccPhatLag(a, b);
    const double offset = (k0 + n / 2 + lag) - (j0 + n / 2);  // device-1 index minus device-0 index
    const double expected = k_expected - t * fs;
    std::printf("t=%.1f s: offset %.3f samples, expected %.3f\n", t, offset, expected);
    EXPECT_NEAR(offset, expected, 0.25);
    if (t > 1) {
      EXPECT_NEAR(offset - previous, fs * delta, 0.3);  // +6.4 samples per second
    }
    previous = offset;
  }
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
