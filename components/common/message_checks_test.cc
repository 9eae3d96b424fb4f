#include "common/message_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sarmap/message_samples.h"

namespace sarmap {
namespace common {
namespace {

TEST(MessageChecksTest, CatchesInconsistentAudio) {
  sarmap::audio_frame_t a{};
  a.header.utime = 1;
  a.sample_rate_hz = 16000;
  a.num_channels = 4;
  a.num_samples = 10;
  a.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
  a.num_values = 40;
  a.samples.resize(40);
  EXPECT_EQ(CheckMessage(a), "");
  a.num_channels = 3;  // 3 * 10 != 40
  EXPECT_NE(CheckMessage(a), "");
  a.num_channels = 0;
  EXPECT_NE(CheckMessage(a), "");
}

TEST(MessageChecksTest, CatchesNonFinitePoseAndBadQuaternion) {
  sarmap::pose_t p{};
  p.orientation[0] = 1.0;
  EXPECT_EQ(CheckMessage(p), "");
  p.position_m[1] = NAN;
  EXPECT_NE(CheckMessage(p), "");
  p.position_m[1] = 0;
  p.orientation[0] = 2.0;
  EXPECT_NE(CheckMessage(p), "");
}

TEST(MessageChecksTest, CatchesBadScans) {
  sarmap::laser_scan_t s{};
  s.angle_increment_rad = 0.01;
  s.range_max_m = 5;
  s.num_ranges = 3;
  s.ranges_m = {1.0f, NAN, 2.0f};  // NaN ranges mean "no return" and are fine
  EXPECT_EQ(CheckMessage(s), "");
  s.num_intensities = 2;
  s.intensities = {1, 2};
  EXPECT_NE(CheckMessage(s), "");
}

TEST(MessageChecksTest, RandomSamplesNeverCrashTheChecks) {
  std::mt19937_64 rng(7);
#define CHECK_SAMPLE(T)                \
  for (int i = 0; i < 20; ++i) {       \
    sarmap::T m;                       \
    sarmap::samples::Fill(m, rng);     \
    (void)CheckMessage(m);             \
  }
  SARMAP_FOR_EACH_MESSAGE_TYPE(CHECK_SAMPLE)
#undef CHECK_SAMPLE
}

}  // namespace
}  // namespace common
}  // namespace sarmap
