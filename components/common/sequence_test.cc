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

TEST(PublisherSequencesTest, KeepsEachPublishersSequenceApart) {
  // Two publishers on one channel, interleaved: neither loses anything.
  PublisherSequences s;
  for (int64_t seq = 0; seq < 50; ++seq) {
    EXPECT_EQ(s.Observe("people-map", seq), 0);
    if (seq % 5 == 0) {
      EXPECT_EQ(s.Observe("sound-map", seq / 5), 0);
    }
  }
  EXPECT_EQ(s.gaps(), 0);
  EXPECT_EQ(s.reordered(), 0);
  EXPECT_EQ(s.received(), 60);
  EXPECT_EQ(s.publishers(), 2u);
  // One of them loses two: counted, and not hidden by the other's numbers.
  EXPECT_EQ(s.Observe("sound-map", 12), 2);
  EXPECT_EQ(s.Observe("people-map", 50), 0);
  EXPECT_EQ(s.gaps(), 2);

  // The same interleaving through one tracker reads gaps and late messages that are not there.
  SequenceTracker one;
  for (int64_t seq = 0; seq < 50; ++seq) {
    one.Observe(seq);
    if (seq % 5 == 0 && seq > 0) one.Observe(seq / 5);
  }
  EXPECT_GT(one.reordered(), 0);
}

TEST(PublisherSequencesTest, MadeUpPublishersShareOneTracker) {
  PublisherSequences s;
  for (size_t i = 0; i < 10 * PublisherSequences::kMaxPublishers; ++i)
    s.Observe("publisher-" + std::to_string(i), 0);
  EXPECT_LE(s.publishers(), PublisherSequences::kMaxPublishers);
  EXPECT_EQ(s.received(), static_cast<int64_t>(10 * PublisherSequences::kMaxPublishers));
}

}  // namespace
}  // namespace common
}  // namespace sarmap
