#include "sound_map/data_association.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace sound_map {
namespace {

TEST(SourceAssociator, TrackThenSilenceThenSignature) {
  SourceAssociator a({});
  const std::vector<double> voice_a = {1.0, 0.2, -0.3, 0.1}, voice_b = {-0.2, 1.0, 0.4, -0.5};
  // Two sources mapped from tracks 1 and 2.
  a.Commit("kinect", 1, 10, voice_a);
  a.Commit("kinect", 2, 20, voice_b);
  EXPECT_EQ(a.Associate("kinect", 1, {}, {10, 20}, [](int64_t) { return 100.0; }).source, 10);
  // Source 10 fell silent; a new track 7 arrives whose bearing fits both sources, and its
  // spectrum is voice A: re-associated to 10, not 20.
  auto both_fit = [](int64_t) { return 1.0; };
  auto d = a.Associate("kinect", 7, {0.95, 0.25, -0.3, 0.1}, {10, 20}, both_fit);
  EXPECT_EQ(d.source, 10);
  EXPECT_TRUE(d.reassociated);
  // Outside the bearing gate: a new source.
  EXPECT_EQ(a.Associate("kinect", 8, voice_a, {10, 20}, [](int64_t) { return 50.0; }).source, -1);
  // Fits the bearing of 20 only, but sounds like A: refused by the signature gate.
  EXPECT_EQ(a.Associate("kinect", 9, voice_a, {20}, both_fit).source, -1);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
