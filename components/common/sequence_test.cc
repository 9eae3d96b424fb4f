#include "common/sequence.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace common {
namespace {

TEST(SequenceTrackerTest, CountsGapsReorderingAndRestarts) {
  SequenceTracker t;
  EXPECT_EQ(t.Observe(5), 0);  // the first seen sets the origin
  EXPECT_EQ(t.Observe(6), 0);
  EXPECT_EQ(t.Observe(9), 2);  // 7, 8 missing
  EXPECT_EQ(t.gaps(), 2);
  t.Observe(8);  // late: no longer missing
  EXPECT_EQ(t.gaps(), 1);
  EXPECT_EQ(t.reordered(), 1);
  t.Observe(0);  // publisher restarted
  EXPECT_EQ(t.restarts(), 1);
  EXPECT_EQ(t.Observe(1), 0);
  EXPECT_EQ(t.received(), 6);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
