#include "common/compression.h"

#include <gtest/gtest.h>

#include <random>

#include "common/image_codec.h"
#include "common/image_messages.h"

namespace sarmap {
namespace common {
namespace {

std::vector<uint16_t> SyntheticDepth(int w, int h) {
  std::vector<uint16_t> depth(static_cast<size_t>(w) * h);
  std::mt19937 rng(3);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      depth[r * w + c] = (r % 50 == 0) ? 0 : static_cast<uint16_t>(800 + 3 * r + c + rng() % 8);
  return depth;
}

TEST(DepthCompressionTest, IsLosslessAndSmaller) {
  const int w = 640, h = 480;
  const auto depth = SyntheticDepth(w, h);
  const auto packed = CompressDepth(depth.data(), w, h);
  EXPECT_LT(packed.size(), depth.size() * 2 / 2);  // at least 2:1 on a smooth noisy surface
  std::vector<uint16_t> back(depth.size());
  std::string error;
  ASSERT_TRUE(DecompressDepth(packed.data(), packed.size(), w, h, back.data(), &error)) << error;
  EXPECT_EQ(back, depth);
}

TEST(DepthCompressionTest, RejectsCorruptAndWrongSize) {
  const auto depth = SyntheticDepth(64, 48);
  auto packed = CompressDepth(depth.data(), 64, 48);
  std::vector<uint16_t> out(64 * 48);
  std::string error;
  EXPECT_FALSE(DecompressDepth(packed.data(), packed.size(), 64, 47, out.data(), &error));
  EXPECT_FALSE(DecompressDepth(packed.data(), packed.size() / 2, 64, 48, out.data(), &error));
  packed[packed.size() / 2] ^= 0xff;
  packed[packed.size() / 2 + 1] ^= 0x55;
  // Corruption inside the frame either fails the checks or decodes to something else, but
  // never crashes or overruns.
  DecompressDepth(packed.data(), packed.size(), 64, 48, out.data(), &error);
}

TEST(ImageMessagesTest, DepthAndColourRoundTrip) {
  sarmap::header_t header;
  header.utime = 1;
  header.seq = 0;
  header.frame = "camera";
  sarmap::camera_intrinsics_t intr{};
  const int w = 64, h = 48;
  const auto depth = SyntheticDepth(w, h);
  std::vector<uint16_t> back;
  std::string error;
  for (bool compress : {true, false}) {
    const auto msg = MakeDepthImage(header, intr, depth.data(), w, h, compress);
    ASSERT_TRUE(DecodeDepthImage(msg, &back, &error)) << error;
    EXPECT_EQ(back, depth);
  }
  std::vector<uint8_t> rgb(w * h * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>((i / 3) % w * 4);
  const auto jpeg = MakeColorImage(header, intr, rgb.data(), w, h, 95);
  EXPECT_EQ(+jpeg.compression, +sarmap::image_t::COMPRESSION_JPEG);
  std::vector<uint8_t> decoded;
  ASSERT_TRUE(DecodeColorImage(jpeg, &decoded, &error)) << error;
  double err = 0;
  for (size_t i = 0; i < rgb.size(); ++i) err += std::abs(int(rgb[i]) - int(decoded[i]));
  EXPECT_LT(err / rgb.size(), 4.0);  // JPEG at q95 is close
  auto broken = jpeg;
  broken.data.resize(broken.data.size() / 3);
  broken.size = static_cast<int32_t>(broken.data.size());
  EXPECT_FALSE(DecodeColorImage(broken, &decoded, &error) && decoded == rgb);
  auto wrong = MakeColorImage(header, intr, rgb.data(), w, h, 0);
  wrong.width = w + 1;
  EXPECT_FALSE(DecodeColorImage(wrong, &decoded, &error));
}

}  // namespace
}  // namespace common
}  // namespace sarmap
