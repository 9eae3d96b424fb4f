#include "sound_localisation/doa_estimators.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "sound_localisation/localiser.h"
#include "sound_localisation/test_util.h"
#include "sound_localisation/testing/room_simulation.h"

namespace sarmap {
namespace sound {
namespace {

using testing_util::LoadArray;
using testing_util::Speech;
using testing_util::WhiteNoise;

// Statistics of all frames of a simulated recording.
BlockStatistics AllFrames(const Localiser& loc, const std::vector<std::vector<float>>& mics) {
  MultichannelStft stft(static_cast<int>(mics.size()), loc.options().fft_size,
                        loc.options().hop_size);
  BlockStatistics stats = loc.MakeStatistics();
  stft.PushFloat(mics, 0, mics[0].size(),
                 [&](const Eigen::MatrixXcf& s, int64_t) { loc.Accumulate(s, &stats); });
  return stats;
}

Eigen::Matrix3Xd Place(const ArrayGeometry& g, const Eigen::Vector3d& centre) {
  return g.positions_m.colwise() + centre;
}

TEST(GccPhat, RecoversIntegerAndFractionalDelay) {
  // Two "microphones": channel 1 is channel 0 delayed by 3.5 samples (through a sinc RIR).
  Room room;
  room.max_rir_s = 0.01;
  std::vector<float> x = WhiteNoise(16000, 1);
  std::vector<float> h0(160, 0.0f), h1(160, 0.0f);
  auto frac = [](std::vector<float>& h, double t) {
    for (int n = 0; n < static_cast<int>(h.size()); ++n) {
      const double d = n - t;
      h[n] = static_cast<float>(std::abs(d) < 1e-9 ? 1.0 : std::sin(M_PI * d) / (M_PI * d));
    }
  };
  frac(h0, 20.0);
  frac(h1, 23.5);
  std::vector<std::vector<float>> mics = {Convolve(x, h0), Convolve(x, h1)};
  common::MicArrayOptions a;
  a.geometry = "linear";
  a.mic_positions_m = {0, 0, 0, 0.2, 0, 0};
  LocaliserOptions o;
  o.min_frequency_hz = 100;
  Localiser loc(ArrayGeometry::FromOptions(a), o, nullptr);
  const BlockStatistics stats = AllFrames(loc, mics);
  // tau_0 - tau_1 = -3.5 samples.
  EXPECT_NEAR(GccPhatTdoa(stats, 0, 1, 0.001, 8) * 16000, -3.5, 0.1);
}

TEST(SrpPhatAndMusic, AnechoicSingleSourceOnPlanarArray) {
  const ArrayGeometry g = LoadArray("respeaker4");
  Room room;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  const double az = DegToRad(-130), el = DegToRad(25);
  const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const auto mics = SimulateRoom(room, Place(g, centre), {{centre + 1.5 * u, WhiteNoise(16000, 2)}},
                                 16000, 0.001, 3);
  for (const std::string method : {"srp_phat", "music", "gevd_music", "gcc_phat"}) {
    LocaliserOptions o;
    o.method = method;
    o.max_sources = 1;
    Localiser loc(g, o, nullptr);
    const auto est = loc.Estimate(AllFrames(loc, mics));
    ASSERT_EQ(est.size(), 1u) << method;
    EXPECT_NEAR(RadToDeg(WrapAngle(est[0].direction.azimuth_rad - az)), 0.0, 1.0) << method;
    EXPECT_NEAR(RadToDeg(est[0].direction.elevation_rad - el), 0.0, 2.0) << method;
  }
}

TEST(Esprit, UniformLinearArrayAngles) {
  const ArrayGeometry g = LoadArray("ps3eye");
  ASSERT_GT(g.UniformSpacing(), 0);
  Room room;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  LocaliserOptions o;
  o.method = "esprit";
  o.min_frequency_hz = 300;
  Localiser loc(g, o, nullptr);
  for (double theta_deg : {40.0, 75.0, 110.0, 140.0}) {
    const double t = DegToRad(theta_deg);
    const Eigen::Vector3d u(std::cos(t), std::sin(t), 0);  // angle t to the x axis
    const auto mics = SimulateRoom(room, Place(g, centre),
                                   {{centre + 2.0 * u, WhiteNoise(16000, 4)}}, 16000, 0.001, 5);
    const auto est = loc.Estimate(AllFrames(loc, mics));
    ASSERT_FALSE(est.empty());
    EXPECT_NEAR(RadToDeg(est[0].direction.azimuth_rad), theta_deg, 2.0);
  }
  // Not a uniform linear array: a clear error.
  LocaliserOptions bad;
  bad.method = "esprit";
  EXPECT_THROW(Localiser(LoadArray("kinect"), bad, nullptr), std::invalid_argument);
}

// SRP-PHAT through the pairs' correlations equals the direct steering; a fricative-like source
// (4.5-6.5 kHz noise, above the ReSpeaker's 3.75 kHz aliasing limit) at az 180 / el 20 has a
// grating lobe near az 0 / el 60. Subtracting the source's whole correlation (Subtract, CLEAN)
// removes it (so does zeroing the main lobe's lags here, with one anechoic plane wave; on the
// real recordings it did not).
TEST(CorrelationSrp, MatchesSrpPhatAndCleanRemovesTheGratingLobe) {
  const ArrayGeometry g = LoadArray("respeaker4");
  const double fs = g.sample_rate_hz;
  // Band-pass FIR (windowed sinc difference) for 4.5-6.5 kHz.
  std::vector<float> h(129);
  for (int n = 0; n < 129; ++n) {
    const double t = n - 64;
    auto lowpass = [&](double fc) {
      return t == 0 ? 2 * fc / fs : std::sin(2 * M_PI * fc / fs * t) / (M_PI * t);
    };
    h[n] = static_cast<float>((lowpass(6500) - lowpass(4500)) *
                              (0.5 - 0.5 * std::cos(2 * M_PI * n / 128)));
  }
  const std::vector<float> x = Convolve(WhiteNoise(16000, 5), h);
  const Direction source{DegToRad(180), DegToRad(20)};
  const Eigen::Vector3d u0 = g.Unit(DoaKind::kAzimuthElevation, source);
  const Eigen::VectorXd delays = g.Delays(u0);
  std::vector<std::vector<float>> mics(g.num_mics(), std::vector<float>(x.size(), 0.0f));
  for (int m = 0; m < g.num_mics(); ++m)
    testing_util::AddDelayed(x, 20 + delays[m] * fs, 1.0, &mics[m]);
  LocaliserOptions o;
  Localiser loc(g, o, nullptr);
  const BlockStatistics stats = AllFrames(loc, mics);
  const SrpPhat direct(g, stats);
  CorrelationSrp corr(g, o.fft_size, stats.bin_lo, stats.bin_hi);
  corr.SetBlock(stats);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> az(-M_PI, M_PI), el(0, M_PI / 2);
  double worst = 0;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d u = g.Unit(DoaKind::kAzimuthElevation, {az(rng), el(rng)});
    worst = std::max(worst, std::abs(corr(u) - direct(u)));
  }
  // Away from the source (> 60 deg): its grating lobe.
  SearchOptions so;
  const std::vector<Eigen::Vector3d> units = SearchGridUnits(g, so);
  auto far_max = [&](const CorrelationSrp& c) {
    double best = -1;
    for (const auto& u : units)
      if (std::acos(std::clamp(u.dot(u0), -1.0, 1.0)) > DegToRad(60)) best = std::max(best, c(u));
    return best;
  };
  const double peak = corr(u0), lobe = far_max(corr);
  CorrelationSrp zeroed = corr, cleaned = corr;
  zeroed.Suppress(u0, fs / (2 * (o.min_frequency_hz + o.max_frequency_hz)));
  cleaned.Subtract(u0);
  const double lobe_zeroed = far_max(zeroed), lobe_cleaned = far_max(cleaned);
  std::printf(
      "|correlation - direct| <= %.2g; source %.3f, grating lobe %.3f; after zeroing %.3f, after "
      "clean %.3f\n",
      worst, peak, lobe, lobe_zeroed, lobe_cleaned);
  EXPECT_LT(worst, 2e-3);
  EXPECT_GT(lobe, 0.3 * peak);
  EXPECT_LT(lobe_cleaned, 0.3 * lobe);
}

// Several simultaneous talkers (real speech, different speakers) in a mildly reverberant
// room, 8-mic 3D array.
void MultiTalker(int num_talkers) {
  if (Speech(0).empty()) GTEST_SKIP() << "shared data missing: audio/cmu_arctic";
  const ArrayGeometry g = LoadArray("cube8");
  Room room;
  room.rt60_s = 0.25;
  room.max_rir_s = 0.2;
  const Eigen::Vector3d centre(3.1, 2.4, 1.3);
  const std::vector<double> azimuths = {40, 160, -80};
  std::vector<SimSource> sources;
  for (int i = 0; i < num_talkers; ++i) {
    const double a = DegToRad(azimuths[i]);
    sources.push_back({centre + 1.5 * Eigen::Vector3d(std::cos(a), std::sin(a), 0), Speech(i)});
  }
  const auto mics = SimulateRoom(room, Place(g, centre), sources, 40000, 0.002, 6);
  for (const std::string method : {"srp_phat", "music"}) {
    LocaliserOptions o;
    o.method = method;
    o.search = "azimuth";
    o.min_frequency_hz = 300;
    o.max_frequency_hz = 7000;
    o.max_sources = num_talkers;
    o.music_num_sources = num_talkers;
    o.min_peak_ratio = 0.2;
    Localiser loc(g, o, nullptr);
    const auto est = loc.Estimate(AllFrames(loc, mics));
    std::printf("%d talkers, %s:", num_talkers, method.c_str());
    for (const auto& e : est) std::printf(" %.1f", RadToDeg(e.direction.azimuth_rad));
    std::printf("  (truth");
    for (int i = 0; i < num_talkers; ++i) std::printf(" %.0f", azimuths[i]);
    std::printf(")\n");
    ASSERT_EQ(static_cast<int>(est.size()), num_talkers) << method;
    for (int i = 0; i < num_talkers; ++i) {
      double best = 1e9;
      for (const auto& e : est)
        best = std::min(
            best, std::abs(RadToDeg(WrapAngle(e.direction.azimuth_rad - DegToRad(azimuths[i])))));
      EXPECT_LE(best, 5.0) << method << " talker " << i;
    }
  }
}

TEST(MultiSource, TwoSimultaneousTalkers) { MultiTalker(2); }
TEST(MultiSource, ThreeSimultaneousTalkers) { MultiTalker(3); }

// Kinect linear array, room with RT60 0.4 s, talker at broadside angles -60..60 deg.
TEST(KinectReverberantRoom, MeanErrorOverBroadsideAngles) {
  if (Speech(0).empty()) GTEST_SKIP() << "shared data missing: audio/cmu_arctic";
  const ArrayGeometry g = LoadArray("kinect");
  Room room;
  room.rt60_s = 0.4;
  room.max_rir_s = 0.3;
  const Eigen::Vector3d centre(2.2, 1.6, 1.0);
  const std::vector<std::string> methods = {"srp_phat", "gcc_phat", "music"};
  std::vector<double> sum(methods.size(), 0.0), worst(methods.size(), 0.0);
  int n = 0;
  for (int phi_deg = -60; phi_deg <= 60; phi_deg += 10, ++n) {
    // Broadside angle phi from +y; the axis is x, so the angle to the axis is 90 - phi.
    const double phi = DegToRad(phi_deg);
    const Eigen::Vector3d u(std::sin(phi), std::cos(phi), 0);
    const auto mics =
        SimulateRoom(room, Place(g, centre), {{centre + 1.5 * u, Speech(n)}}, 24000, 0.002, 7 + n);
    for (size_t m = 0; m < methods.size(); ++m) {
      LocaliserOptions o;
      o.method = methods[m];
      o.min_frequency_hz = 300;
      o.max_frequency_hz = 4000;
      o.max_sources = 1;
      Localiser loc(g, o, nullptr);
      const auto est = loc.Estimate(AllFrames(loc, mics));
      ASSERT_FALSE(est.empty());
      const double err = std::abs(90.0 - RadToDeg(est[0].direction.azimuth_rad) - phi_deg);
      sum[m] += err;
      worst[m] = std::max(worst[m], err);
    }
  }
  for (size_t m = 0; m < methods.size(); ++m)
    std::printf(
        "Kinect RT60 0.4 s, %s: mean error %.2f deg, max %.2f deg over %d angles (-60..60 step "
        "10)\n",
        methods[m].c_str(), sum[m] / n, worst[m], n);
  EXPECT_LE(sum[0] / n, 3.5);
}

// A stationary noise source (a fan, a motor) at azimuth 100 deg and a talker at -40 deg who
// starts after 1.5 s: GEVD-MUSIC whitens with the noise covariance learnt before the talker
// (non-speech frames) and finds the talker. The figures of SEVD-MUSIC and SRP-PHAT are printed
// for comparison (SRP-PHAT, which weights all bins equally, is drawn to the white noise).
TEST(GevdMusic, IgnoresAStationaryDirectionalNoise) {
  auto speech = Speech(1);
  if (speech.empty()) GTEST_SKIP() << "shared data missing: audio/cmu_arctic";
  const ArrayGeometry g = LoadArray("respeaker4");
  Room room;
  room.rt60_s = 0.2;
  room.max_rir_s = 0.15;
  const Eigen::Vector3d centre(3, 2.5, 1.0);
  const size_t lead = 24000, n = lead + speech.size();
  std::vector<float> talker(n, 0.0f);
  std::copy(speech.begin(), speech.end(), talker.begin() + lead);
  auto dir = [](double az_deg, double el_deg) {
    const double a = DegToRad(az_deg), e = DegToRad(el_deg);
    return Eigen::Vector3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
  };
  const auto mics = SimulateRoom(room, Place(g, centre),
                                 {{centre + 1.5 * dir(-40, 20), talker, 1.0},
                                  {centre + 1.5 * dir(100, 20), WhiteNoise(n, 9), 0.3}},
                                 n, 0.001, 10);
  for (const std::string method : {"gevd_music", "music", "srp_phat"}) {
    LocaliserOptions o;
    o.method = method;
    o.max_sources = 1;
    o.activity_snr_db = 3;
    Localiser loc(g, o, nullptr);
    std::vector<LocaliserOutput> outs;
    loc.PushFloat(mics, 0, n, &outs);
    std::vector<double> err;
    for (const auto& out : outs)
      if (!out.directions.empty() && out.end_sample > static_cast<int64_t>(lead) + 4000)
        err.push_back(
            std::abs(RadToDeg(WrapAngle(out.directions[0].direction.azimuth_rad - DegToRad(-40)))));
    std::sort(err.begin(), err.end());
    const double median = err.empty() ? 999 : err[err.size() / 2];
    std::printf(
        "talker -40 deg + stationary noise 100 deg, %s: median azimuth error %.1f deg over %zu "
        "blocks\n",
        method.c_str(), median, err.size());
    if (method == "gevd_music") {
      EXPECT_LE(median, 5.0);
    }
  }
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
