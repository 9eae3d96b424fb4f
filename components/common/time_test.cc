#include "common/time.h"

#include <gtest/gtest.h>

#include <vector>

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

}  // namespace
}  // namespace common
}  // namespace sarmap
