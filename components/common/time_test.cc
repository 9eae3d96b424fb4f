#include "common/time.h"

#include <gtest/gtest.h>

#include <vector>

#include "common/stamp_decimator.h"

namespace sarmap {
namespace common {
namespace {

TEST(TimeTest, Conversions) {
  EXPECT_EQ(SecondsToUtime(1.5), 1500000);
  EXPECT_EQ(SecondsToUtime(-0.000001), -1);
  EXPECT_DOUBLE_EQ(UtimeToSeconds(2500000), 2.5);
}

TEST(TimeOrderedQueueTest, ReleasesInOrderAfterTheDelayAndDropsLateItems) {
  TimeOrderedQueue<int> q(100);
  std::vector<Utime> out;
  auto sink = [&](Utime t, int&) { out.push_back(t); };
  q.Push(1000, 1);
  q.Push(900, 2);  // reordered but not late
  q.Push(1050, 3);
  q.Release(sink);  // releases <= 1050 - 100
  EXPECT_EQ(out, std::vector<Utime>({900}));
  q.Push(1200, 4);
  q.Release(sink);  // <= 1100
  EXPECT_EQ(out, std::vector<Utime>({900, 1000, 1050}));
  EXPECT_FALSE(q.Push(1010, 5));  // older than what was released: too late
  EXPECT_EQ(q.dropped_late(), 1);
  EXPECT_EQ(q.reordered(), 1);
  q.Flush(sink);
  EXPECT_EQ(out.back(), 1200);
  EXPECT_EQ(q.size(), 0u);
}

TEST(TimeOrderedQueueTest, ALateStreamIsKeptInItsOwnOrder) {
  // Odometry (stream 1) arrives on time; scans made from depth frames (stream 0) arrive late.
  TimeOrderedQueue<int> q(100);
  std::vector<std::pair<Utime, int>> out;
  auto sink = [&](Utime t, int& v) { out.push_back({t, v}); };
  for (Utime t = 1000; t <= 1500; t += 100) q.Push(t, 1, /*stream=*/1);
  q.Release(sink);  // odometry up to 1400 released
  EXPECT_EQ(out.size(), 5u);
  EXPECT_TRUE(q.Push(1050, 0, /*stream=*/0));  // older than released odometry: still taken
  EXPECT_TRUE(q.Push(1150, 0, /*stream=*/0));
  q.Release(sink);
  ASSERT_EQ(out.size(), 7u);
  EXPECT_EQ(out[5], std::make_pair(Utime{1050}, 0));
  EXPECT_EQ(out[6], std::make_pair(Utime{1150}, 0));
  EXPECT_FALSE(q.Push(1100, 0, /*stream=*/0));  // older than its own stream's last: too late
  EXPECT_FALSE(q.Push(1350, 1, /*stream=*/1));
  EXPECT_EQ(q.dropped_late(), 2);
}

// A clock-only input releases what waits, as a newer item would.
TEST(TimeOrderedQueueTest, AdvanceToReleasesWithoutAnItem) {
  TimeOrderedQueue<int> q(100);
  std::vector<int> out;
  q.Push(1000, 1);
  q.Release([&](Utime, int& v) { out.push_back(v); });
  EXPECT_TRUE(out.empty());
  q.AdvanceTo(1050);
  q.Release([&](Utime, int& v) { out.push_back(v); });
  EXPECT_TRUE(out.empty());
  q.AdvanceTo(1100);
  q.Release([&](Utime, int& v) { out.push_back(v); });
  EXPECT_EQ(out, std::vector<int>{1});
}

// A job that took 0.5 s may run again 4.5 s after it ended at 10 %; a quick one at once.
TEST(BusyLimiterTest, KeepsAGrowingJobToItsFractionOfTheWallTime) {
  BusyLimiter limiter(0.1);
  EXPECT_TRUE(limiter.Allowed(0.0));
  limiter.Ran(10.0, 10.5);
  EXPECT_FALSE(limiter.Allowed(14.9));
  EXPECT_TRUE(limiter.Allowed(15.0));
  limiter.Ran(15.0, 15.001);
  EXPECT_TRUE(limiter.Allowed(15.01));
  BusyLimiter unlimited(1.0);
  unlimited.Ran(0.0, 3.0);
  EXPECT_TRUE(unlimited.Allowed(3.0));
}

// A 30 Hz camera with jittered stamps thinned to 15 Hz keeps every second frame; 0 keeps all;
// a stamp going back is taken and starts again.
TEST(StampDecimatorTest, KeepsEverySecondFrameOfAJitteredThirtyHertzStream) {
  StampDecimator half(15.0);
  const Utime jitter_us[] = {0, 3000, -2500, 1500, -3000, 2000, 0, -1000};
  std::vector<int> kept;
  for (int i = 0; i < 8; ++i) {
    if (half.Take(1000000 + i * 33333 + jitter_us[i])) kept.push_back(i);
  }
  EXPECT_EQ(kept, (std::vector<int>{0, 2, 4, 6}));
  EXPECT_EQ(half.skipped(), 4);
  EXPECT_TRUE(half.Take(500000));  // back in time
  EXPECT_FALSE(half.Take(520000));

  StampDecimator all(0.0);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(all.Take(1000000 + i * 1000));
  EXPECT_EQ(all.skipped(), 0);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
