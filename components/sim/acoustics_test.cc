#include "sim/acoustics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace sarmap {
namespace sim {
namespace {

TEST(AcousticsTest, EyringAndSabineInvertTheirFormulas) {
  const double V = 8 * 6 * 2.7, S = 2 * (8 * 6 + 8 * 2.7 + 6 * 2.7);
  const double alpha = EyringAbsorptionForRt60(V, S, 0.45);
  EXPECT_NEAR(EyringRt60(V, S, alpha), 0.45, 1e-9);
  EXPECT_NEAR(0.161 * V / (S * SabineAbsorptionForRt60(V, S, 0.45)), 0.45, 1e-9);
  EXPECT_GT(SabineAbsorptionForRt60(V, S, 0.45), alpha);  // Sabine needs more absorption
}

TEST(AcousticsTest, FractionalDelayPeaksAtTheDelay) {
  for (double delay : {20.0, 20.25, 20.5, 37.8}) {
    std::vector<float> h;
    AddFractionalDelay(&h, delay, 1.0, 16);
    // Low-frequency group delay sum(n h) / sum(h) is the delay; the DC gain is 1.
    double num = 0, den = 0;
    for (size_t n = 0; n < h.size(); ++n) {
      num += n * h[n];
      den += h[n];
    }
    EXPECT_NEAR(num / den, delay, 0.02) << delay;
    EXPECT_NEAR(den, 1.0, 0.01) << delay;
  }
}

// The reverberation decay of the computed impulse response (Schroeder backward
// integration) matches the RT60 the absorption was set from (Eyring) within 20 %.
TEST(AcousticsTest, ImageSourceDecayMatchesConfiguredRt60) {
  struct Case {
    Eigen::Vector3d size;
    double rt60;
  };
  for (const Case& c : {Case{{8, 6, 2.7}, 0.45}, Case{{8, 6, 2.7}, 0.8}, Case{{5, 4, 3}, 0.3}}) {
    ShoeboxRoom room;
    room.max = c.size;
    // Eyring alone, for the record (a specular shoebox decays slower than a diffuse field).
    const double eyring = EyringAbsorptionForRt60(room.Volume(), room.Surface(), c.rt60);
    SetUniformRt60(&room, c.rt60);
    std::printf("absorption: Eyring %.3f, refined %.3f\n", eyring, 1 - room.beta[0] * room.beta[0]);
    RirOptions options;
    options.max_length_s = 1.1 * c.rt60;
    const std::vector<float> h = ImageSourceRir(room, {2.0, 1.5, 1.2}, {5.1, 3.9, 0.7}, options);
    const double t20 = SchroederRt60(h, options.sample_rate_hz, -5, -25);
    std::printf("room %.1fx%.1fx%.1f: configured RT60 %.2f s, Schroeder T20 %.3f s (%.1f %%)\n", c.size.x(),
                c.size.y(), c.size.z(), c.rt60, t20, 100 * (t20 - c.rt60) / c.rt60);
    EXPECT_NEAR(t20, c.rt60, 0.2 * c.rt60);
  }
}

// Early (order <= 2) and late (order > 2) parts add up to the whole response.
TEST(AcousticsTest, EarlyAndLatePartsSumToTheWhole) {
  ShoeboxRoom room;
  room.max = Eigen::Vector3d(6, 5, 3);
  SetUniformRt60(&room, 0.3);
  RirOptions all;
  all.max_length_s = 0.3;
  RirOptions early = all, late = all;
  early.max_order = all.exact_order;
  late.min_order = all.exact_order + 1;
  const Eigen::Vector3d s(1.2, 3.1, 1.4), m(4.4, 1.7, 0.9);
  const auto h = ImageSourceRir(room, s, m, all), he = ImageSourceRir(room, s, m, early),
             hl = ImageSourceRir(room, s, m, late);
  ASSERT_EQ(h.size(), he.size());
  ASSERT_EQ(h.size(), hl.size());
  double worst = 0;
  for (size_t k = 0; k < h.size(); ++k) worst = std::max(worst, static_cast<double>(std::abs(h[k] - he[k] - hl[k])));
  EXPECT_LT(worst, 1e-6);
}

TEST(AcousticsTest, DirectPathHasOneOverRAttenuation) {
  ShoeboxRoom room;
  room.max = Eigen::Vector3d(10, 10, 10);
  RirOptions options;
  options.reverb = false;
  options.max_length_s = 0.1;
  double reference = 0;
  (void)reference;
  for (double r : {1.0, 2.0, 4.0, 7.3}) {
    const std::vector<float> h = ImageSourceRir(room, {1, 5, 5}, {1 + r, 5, 5}, options);
    double gain = 0;
    for (float v : h) gain += v;
    // The pulse's area (DC gain) is its amplitude: 1/r.
    if (reference == 0) reference = gain;
    EXPECT_NEAR(gain * r, 1.0, 0.01) << r;
  }
}

TEST(AcousticsTest, MultiConvolverMatchesDirectConvolution) {
  std::mt19937 gen(3);
  std::normal_distribution<float> n(0, 1);
  const int block = 256, len = 700;
  std::vector<std::vector<float>> filters(2, std::vector<float>(len));
  for (auto& f : filters) for (float& v : f) v = n(gen) * 0.1f;
  std::vector<float> x(block * 8);
  for (float& v : x) v = n(gen);
  MultiConvolver conv(block, len, 2);
  conv.SetFilters(filters);
  std::vector<std::vector<float>> y(2, std::vector<float>(x.size(), 0.0f));
  for (size_t b = 0; b < x.size() / block; ++b) {
    conv.Process(&x[b * block], {&y[0][b * block], &y[1][b * block]});
  }
  for (int o = 0; o < 2; ++o) {
    for (size_t k = 0; k < x.size(); k += 97) {
      double ref = 0;
      for (int t = 0; t < len && t <= static_cast<int>(k); ++t) ref += filters[o][t] * x[k - t];
      EXPECT_NEAR(y[o][k], ref, 1e-3);
    }
  }
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
