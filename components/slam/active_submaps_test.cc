// ActiveSubmaps: two overlapping submaps, a new one every scans_per_submap nodes.
#include "slam/active_submaps.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace slam {
namespace {

TEST(ActiveSubmaps, TwoOverlapAndEachFinishedOneHoldsTwiceTheNewOnesNodes) {
  constexpr int kPerSubmap = 3;
  ActiveSubmaps active(kPerSubmap);
  std::vector<int> inserted(10, 0);  // nodes per submap id
  std::vector<int> finished;
  int next_id = 0;
  active.Add(next_id++);
  for (int node = 0; node < 12; ++node) {
    for (int id : active.ids()) ++inserted[id];
    const ActiveSubmaps::Change change = active.AfterInsertion(inserted[active.ids().back()]);
    if (change.finished >= 0) finished.push_back(change.finished);
    if (change.start_new) active.Add(next_id++);
    EXPECT_LE(active.ids().size(), 2u);
  }
  // Each finishes with 6 nodes: 3 before the next one starts, 3 shared with it.
  ASSERT_EQ(finished, std::vector<int>({0, 1, 2}));
  for (int id : finished) EXPECT_EQ(inserted[id], 2 * kPerSubmap);
  EXPECT_EQ(active.matching(), 3);  // the older active one
  EXPECT_EQ(active.ids(), std::vector<int>({3, 4}));
}

TEST(ActiveSubmaps, ARestoredStateGoesOnFromItsSubmaps) {
  ActiveSubmaps active(2);
  active.Restore({7, 8});
  EXPECT_EQ(active.matching(), 7);
  const ActiveSubmaps::Change change = active.AfterInsertion(2);
  EXPECT_EQ(change.finished, 7);
  EXPECT_TRUE(change.start_new);
  EXPECT_EQ(active.ids(), std::vector<int>({8}));
  EXPECT_EQ(active.AfterInsertion(1).finished, -1);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
