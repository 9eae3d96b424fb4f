// FrameAssembler: DEPTH/RGB image_t pairing by utime and decoding, without a bus.

#include "rgbd_odometry/frame_assembler.h"

#include <gtest/gtest.h>

#include "common/image_codec.h"
#include "common/image_messages.h"

namespace sarmap {
namespace rgbd_odometry {
namespace {

constexpr int kW = 64, kH = 48;

camera_intrinsics_t Intrinsics() {
  camera_intrinsics_t in{};
  in.width = kW;
  in.height = kH;
  in.fx = in.fy = 52.5;
  in.cx = 31.5;
  in.cy = 23.5;
  return in;
}

image_t Depth(int64_t utime, uint16_t mm = 1500) {
  header_t h;
  h.utime = utime;
  h.frame = "camera";
  const std::vector<uint16_t> d(kW * kH, mm);
  return common::MakeDepthImage(h, Intrinsics(), d.data(), kW, kH);
}

image_t Color(int64_t utime, int w = kW, int h = kH) {
  header_t hd;
  hd.utime = utime;
  hd.frame = "camera";
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7);
  camera_intrinsics_t in = Intrinsics();
  in.width = w;
  in.height = h;
  return common::MakeColorImage(hd, in, rgb.data(), w, h, 0);  // raw RGB8
}

TEST(FrameAssembler, DepthOnlyWhenColourIsNotNeeded) {
  FrameAssembler a(false, 0.02, 0.2);
  std::vector<RgbdFrame> ready;
  a.AddColor(Color(1000), &ready);  // ignored
  a.AddDepth(Depth(1000, 1234), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].utime, 1000);
  EXPECT_EQ(ready[0].width, kW);
  EXPECT_EQ(ready[0].depth.size(), static_cast<size_t>(kW * kH));
  EXPECT_EQ(ready[0].depth[5], 1234);
  EXPECT_DOUBLE_EQ(ready[0].depth_unit_m, 0.001);
  EXPECT_DOUBLE_EQ(ready[0].camera.fx, 52.5);
  EXPECT_TRUE(ready[0].image.empty());
  EXPECT_EQ(a.total_warnings(), 0);
}

TEST(FrameAssembler, PairsByTimeInEitherOrder) {
  FrameAssembler a(true, 0.02, 0.2);
  std::vector<RgbdFrame> ready;
  a.AddDepth(Depth(1000000), &ready);  // colour comes later
  EXPECT_TRUE(ready.empty());
  a.AddColor(Color(1005000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].image_channels, 3);
  EXPECT_EQ(ready[0].image.size(), static_cast<size_t>(kW * kH * 3));
  EXPECT_EQ(ready[0].image[1], 7);
  a.AddColor(Color(1033333), &ready);  // colour first
  a.AddDepth(Depth(1033333), &ready);
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[1].utime, 1033333);
  EXPECT_EQ(a.total_warnings(), 0);
}

TEST(FrameAssembler, DepthWithoutColourIsDroppedAfterTheWait) {
  FrameAssembler a(true, 0.02, 0.2);
  std::vector<RgbdFrame> ready;
  a.AddDepth(Depth(1000000), &ready);
  a.AddColor(Color(1100000), &ready);  // too far in time for the first depth
  EXPECT_TRUE(ready.empty());
  EXPECT_EQ(a.warnings().count("no_color"), 0u);
  a.AddColor(Color(1300000), &ready);  // message time now 0.3 s past it
  EXPECT_TRUE(ready.empty());
  EXPECT_EQ(a.warnings().at("no_color"), 1);
}

TEST(FrameAssembler, BadInputsAreCountedNotThrown) {
  FrameAssembler a(true, 0.02, 0.2);
  std::vector<RgbdFrame> ready;
  a.AddColor(Color(1000, 32, 24), &ready);
  a.AddDepth(Depth(1000), &ready);
  EXPECT_TRUE(ready.empty());
  EXPECT_EQ(a.warnings().at("color_size_mismatch"), 1);

  image_t broken = Depth(2000);
  broken.data.resize(10);
  broken.size = 10;
  FrameAssembler b(false, 0.02, 0.2);
  b.AddDepth(broken, &ready);
  EXPECT_EQ(b.warnings().at("depth_decode"), 1);
  image_t not_depth = Color(3000);
  b.AddDepth(not_depth, &ready);
  EXPECT_EQ(b.warnings().at("depth_decode"), 2);
  image_t bad_k = Depth(4000);
  bad_k.intrinsics.fx = 0;
  b.AddDepth(bad_k, &ready);
  EXPECT_EQ(b.warnings().at("bad_intrinsics"), 1);
  b.AddDepth(Depth(3500), &ready);  // older than the last depth seen
  EXPECT_EQ(b.warnings().at("depth_out_of_order"), 1);
  EXPECT_TRUE(ready.empty());
  b.AddDepth(Depth(5000), &ready);
  EXPECT_EQ(ready.size(), 1u);
}

TEST(FrameAssembler, TimeGoingFarBackStartsOver) {
  FrameAssembler a(true, 0.02, 0.2);
  std::vector<RgbdFrame> ready;
  a.AddColor(Color(50000000), &ready);
  a.AddDepth(Depth(50000000), &ready);
  ASSERT_EQ(ready.size(), 1u);
  // A log replayed again: its colour arrives first, then its depth, 49 s earlier.
  a.AddColor(Color(1000000), &ready);
  a.AddDepth(Depth(1000000), &ready);
  ASSERT_EQ(ready.size(), 2u);
  EXPECT_EQ(ready[1].utime, 1000000);
  EXPECT_EQ(a.warnings().at("time_restart"), 1);
  // A small step back is a reordered message, dropped.
  a.AddDepth(Depth(900000), &ready);
  EXPECT_EQ(a.warnings().at("depth_out_of_order"), 1);
  a.AddColor(Color(1033333), &ready);
  a.AddDepth(Depth(1033333), &ready);
  EXPECT_EQ(ready.size(), 3u);
}

}  // namespace
}  // namespace rgbd_odometry
}  // namespace sarmap
