#include "slam/packed_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace sarmap {
namespace slam {
namespace {

PointCloud RandomCloud(float reach_m, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-reach_m, reach_m);
  PointCloud points(n);
  for (auto& p : points) p = Eigen::Vector2f(u(rng), u(rng));
  return points;
}

TEST(PackedPointsTest, EachPointIsWithinHalfAStepAndTheStepFitsTheCloud) {
  // Returns within 30 m: a step of 2^-10 m (1 mm), 32767 steps reach 32 m.
  for (const auto& [reach_m, step_m] :
       std::vector<std::pair<float, float>>{{0.9f, std::ldexp(1.0f, -15)},
                                            {30.0f, std::ldexp(1.0f, -10)},
                                            {100.0f, std::ldexp(1.0f, -8)}}) {
    const PointCloud points = RandomCloud(reach_m, 500, 7);
    const PackedPoints packed(points);
    EXPECT_EQ(packed.step_m(), step_m) << reach_m;
    const PointCloud unpacked = packed.Unpack();
    ASSERT_EQ(unpacked.size(), points.size());
    float worst = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      worst = std::max(worst, (unpacked[i] - points[i]).cwiseAbs().maxCoeff());
    }
    EXPECT_LE(worst, 0.5f * step_m * 1.0001f) << reach_m;
    EXPECT_GT(worst, 0.1f * step_m) << reach_m;  // the points were moved: packing is not a copy
    EXPECT_EQ(packed.MemoryBytes(), points.size() * 2 * sizeof(int16_t));
  }
}

TEST(PackedPointsTest, PackingUnpackedPointsAgainGivesTheSamePoints) {
  // What a state file does (floats out, packed again on reading), and what a trimmed node's
  // kept subset does.
  const PointCloud points = RandomCloud(12.0f, 300, 3);
  const PointCloud once = PackedPoints(points).Unpack();
  EXPECT_EQ(PackedPoints(once).Unpack(), once);
  const PointCloud subset(once.begin(), once.begin() + 10);
  EXPECT_EQ(PackedPoints(subset).Unpack(), subset);
  EXPECT_TRUE(PackedPoints(PointCloud()).empty());
  EXPECT_TRUE(PackedPoints(PointCloud()).Unpack().empty());
}

// The stored form round-trips to the same bits; a step that is not a power of two, or an odd
// coordinate count, is refused (a corrupt state file).
TEST(PackedPointsTest, TheStoredFormRoundTripsAndBadOnesAreRefused) {
  const PackedPoints packed(RandomCloud(12.0f, 50, 5));
  const PackedPoints back = PackedPoints::FromRaw(packed.step_m(), packed.raw());
  EXPECT_EQ(back.step_m(), packed.step_m());
  EXPECT_EQ(back.raw(), packed.raw());
  EXPECT_EQ(back.Unpack(), packed.Unpack());
  EXPECT_TRUE(PackedPoints::FromRaw(0.0f, {}).empty());  // never packed
  EXPECT_THROW(PackedPoints::FromRaw(0.0f, {1, 2}), std::invalid_argument);
  EXPECT_THROW(PackedPoints::FromRaw(0.003f, {1, 2}), std::invalid_argument);
  EXPECT_THROW(PackedPoints::FromRaw(-0.5f, {1, 2}), std::invalid_argument);
  EXPECT_THROW(PackedPoints::FromRaw(NAN, {1, 2}), std::invalid_argument);
  EXPECT_THROW(PackedPoints::FromRaw(0.5f, {1, 2, 3}), std::invalid_argument);
}

TEST(PackedPointsTest, ARangeDataKeepsItsOriginAndBothClouds) {
  RangeData data;
  data.origin = Eigen::Vector2f(0.1f, -0.05f);
  data.hits = {{1.0f, 2.0f}, {-3.25f, 0.5f}};
  data.misses = {{4.5f, 0.0f}};
  const RangeData back = PackedRangeData(data).Unpack();
  EXPECT_EQ(back.origin, data.origin);
  ASSERT_EQ(back.hits.size(), 2u);
  ASSERT_EQ(back.misses.size(), 1u);
  EXPECT_NEAR(back.hits[1].x(), -3.25f, 1e-3f);
  EXPECT_NEAR(back.misses[0].x(), 4.5f, 1e-3f);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
