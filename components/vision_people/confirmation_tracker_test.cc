#include "vision_people/confirmation_tracker.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace vision_people {
namespace {

PersonCandidate At(double x, double z) {
  PersonCandidate c;
  c.position_camera = Eigen::Vector3d(x, 0.2, z);
  return c;
}

TEST(ConfirmationTracker, ReportsAfterKOfNFrames) {
  ConfirmationOptions o;
  o.k = 3;
  o.n = 5;
  ConfirmationTracker tracker(o);
  EXPECT_TRUE(tracker.Update({At(0, 3)}).empty());          // 1 of 5
  EXPECT_TRUE(tracker.Update({}).empty());                   // missed
  EXPECT_TRUE(tracker.Update({At(0.05, 3.02)}).empty());    // 2 of 5
  const auto out = tracker.Update({At(0.1, 3.0)});           // 3 of 5
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].hits, 3);
  const int64_t id = out[0].track_id;
  // Same track id while it keeps being seen.
  const auto again = tracker.Update({At(0.12, 3.0)});
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].track_id, id);
}

TEST(ConfirmationTracker, FlickeringFalsePositiveNeverReported) {
  ConfirmationOptions o;  // 3 of 5
  ConfirmationTracker tracker(o);
  int reported = 0;
  for (int f = 0; f < 40; ++f) {
    std::vector<PersonCandidate> d = {At(-1, 4)};               // a real person every frame
    if (f % 3 == 0) d.push_back(At(1.0 + 0.7 * (f % 2), 2.0 + 0.6 * (f % 4)));  // jumps around
    for (const auto& p : tracker.Update(d)) reported += p.person.position_camera.x() > 0;
  }
  EXPECT_EQ(reported, 0);
}

TEST(ConfirmationTracker, TwoPeopleKeepTheirIds) {
  ConfirmationOptions o;
  o.k = 1;
  o.n = 1;
  ConfirmationTracker tracker(o);
  const auto a = tracker.Update({At(-0.5, 3), At(0.5, 3)});
  ASSERT_EQ(a.size(), 2u);
  const auto b = tracker.Update({At(0.55, 3), At(-0.45, 3)});  // listed in the other order
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[0].track_id, a[1].track_id);
  EXPECT_EQ(b[1].track_id, a[0].track_id);
  // Track dropped after n frames unseen: a new id.
  tracker.Update({});
  const auto c = tracker.Update({At(-0.5, 3)});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_NE(c[0].track_id, a[0].track_id);
}

}  // namespace
}  // namespace vision_people
}  // namespace sarmap
