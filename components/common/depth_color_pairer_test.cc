// DepthColorPairer: which depth image goes with which colour image, and when one goes alone.
#include "common/depth_color_pairer.h"

#include <gtest/gtest.h>

namespace sarmap {
namespace common {
namespace {

image_t Image(int64_t utime, int8_t format) {
  image_t im{};
  im.header.utime = utime;
  im.pixel_format = format;
  return im;
}
image_t Depth(int64_t utime) { return Image(utime, image_t::PIXEL_DEPTH_U16); }
image_t Color(int64_t utime) { return Image(utime, image_t::PIXEL_RGB8); }

DepthColorPairing Pairing(bool require_color) {
  DepthColorPairing p;
  p.require_color = require_color;
  p.max_pair_dt_s = 0.02;
  p.color_wait_s = 0.1;
  p.max_pending = 3;
  return p;
}

TEST(DepthColorPairerTest, PairsTheClosestColourInEitherOrder) {
  DepthColorPairer pairer(Pairing(false));
  std::vector<DepthColorPairer::Pair> ready;
  pairer.AddDepth(Depth(1000000), &ready);
  EXPECT_TRUE(ready.empty());  // waits for its colour
  pairer.AddColor(Color(1015000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_TRUE(ready[0].has_color);
  EXPECT_EQ(ready[0].color.header.utime, 1015000);
  pairer.AddColor(Color(1025000), &ready);  // colour first: 8 ms and 3 ms from the depth
  pairer.AddColor(Color(1036000), &ready);
  pairer.AddDepth(Depth(1033000), &ready);
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[1].depth.header.utime, 1033000);
  EXPECT_EQ(ready[1].color.header.utime, 1036000);
  EXPECT_EQ(pairer.total_warnings(), 0);
}

TEST(DepthColorPairerTest, WithoutColourDepthGoesAloneOrIsDroppedAfterTheWait) {
  for (bool require : {false, true}) {
    DepthColorPairer pairer(Pairing(require));
    std::vector<DepthColorPairer::Pair> ready;
    pairer.AddDepth(Depth(1000000), &ready);
    pairer.AddColor(Color(1050000), &ready);  // too far from it, and the wait is not over
    EXPECT_TRUE(ready.empty());
    pairer.AddColor(Color(1150000), &ready);  // message time 0.15 s past the depth
    EXPECT_EQ(ready.size(), require ? 0u : 1u);
    if (!require) {
      EXPECT_FALSE(ready[0].has_color);
    }
    EXPECT_EQ(pairer.warnings().at("no_color"), 1);
  }
}

TEST(DepthColorPairerTest, ABacklogReleasesTheOldestAndFlushReleasesTheRest) {
  DepthColorPairer pairer(Pairing(true));
  std::vector<DepthColorPairer::Pair> ready;
  for (int i = 0; i < 4; ++i) pairer.AddDepth(Depth(1000000 + i * 10000), &ready);
  EXPECT_TRUE(ready.empty());
  EXPECT_EQ(pairer.warnings().at("depth_backlog"), 1);  // 4 waiting, 3 allowed

  DepthColorPairer lenient(Pairing(false));
  for (int i = 0; i < 3; ++i) lenient.AddDepth(Depth(1000000 + i * 10000), &ready);
  EXPECT_TRUE(ready.empty());
  EXPECT_TRUE(lenient.has_pending());
  lenient.Flush(&ready);
  EXPECT_EQ(ready.size(), 3u);
  EXPECT_FALSE(lenient.has_pending());
}

TEST(DepthColorPairerTest, OutOfOrderDepthIsDroppedAndAFarStepBackStartsOver) {
  DepthColorPairer pairer(Pairing(false));
  std::vector<DepthColorPairer::Pair> ready;
  pairer.AddColor(Color(50000000), &ready);
  pairer.AddDepth(Depth(50000000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  pairer.AddDepth(Depth(49900000), &ready);  // 0.1 s back: a reordered message
  EXPECT_EQ(pairer.warnings().at("depth_out_of_order"), 1);
  pairer.AddColor(Color(1000000), &ready);  // a log replayed again, 49 s earlier
  pairer.AddDepth(Depth(1000000), &ready);
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_TRUE(ready[1].has_color);
  EXPECT_EQ(pairer.warnings().at("time_restart"), 1);
}

TEST(DepthColorPairerTest, WithoutColourInUseEveryDepthGoesAtOnce) {
  DepthColorPairing p = Pairing(true);
  p.use_color = false;
  DepthColorPairer pairer(p);
  std::vector<DepthColorPairer::Pair> ready;
  pairer.AddColor(Color(1000000), &ready);
  pairer.AddDepth(Depth(1000000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_FALSE(ready[0].has_color);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
