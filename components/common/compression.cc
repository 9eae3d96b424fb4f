#include "common/compression.h"

#include <zstd.h>

namespace sarmap {
namespace common {

std::vector<uint8_t> CompressDepth(const uint16_t* depth, int width, int height, int level) {
  const size_t n = static_cast<size_t>(width) * height;
  std::vector<uint8_t> planes(2 * n);
  uint8_t* low = planes.data();
  uint8_t* high = planes.data() + n;
  for (int r = 0; r < height; ++r) {
    const uint16_t* row = depth + static_cast<size_t>(r) * width;
    uint16_t prev = r > 0 ? depth[static_cast<size_t>(r - 1) * width] : 0;
    for (int c = 0; c < width; ++c) {
      const uint16_t residual = static_cast<uint16_t>(row[c] - prev);
      prev = row[c];
      const size_t i = static_cast<size_t>(r) * width + c;
      low[i] = static_cast<uint8_t>(residual);
      high[i] = static_cast<uint8_t>(residual >> 8);
    }
  }
  return CompressBytes(planes.data(), planes.size(), level);
}

bool DecompressDepth(const uint8_t* data, size_t size, int width, int height, uint16_t* out,
                     std::string* error) {
  if (width <= 0 || height <= 0) {
    *error = "bad depth image size";
    return false;
  }
  const size_t n = static_cast<size_t>(width) * height;
  std::vector<uint8_t> planes;
  if (!DecompressBytes(data, size, 2 * n, &planes, error)) return false;
  const uint8_t* low = planes.data();
  const uint8_t* high = planes.data() + n;
  for (int r = 0; r < height; ++r) {
    uint16_t prev = r > 0 ? out[static_cast<size_t>(r - 1) * width] : 0;
    for (int c = 0; c < width; ++c) {
      const size_t i = static_cast<size_t>(r) * width + c;
      prev = static_cast<uint16_t>(prev + (low[i] | (high[i] << 8)));
      out[i] = prev;
    }
  }
  return true;
}

std::vector<uint8_t> CompressBytes(const uint8_t* data, size_t size, int level) {
  std::vector<uint8_t> out(ZSTD_compressBound(size));
  const size_t written = ZSTD_compress(out.data(), out.size(), data, size, level);
  // Only fails on a too-small buffer, which compressBound rules out.
  out.resize(ZSTD_isError(written) ? 0 : written);
  return out;
}

bool DecompressBytes(const uint8_t* data, size_t size, size_t expected_size,
                     std::vector<uint8_t>* out, std::string* error) {
  const unsigned long long content = ZSTD_getFrameContentSize(data, size);
  if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN) {
    *error = "not a zstd frame";
    return false;
  }
  if (content != expected_size) {
    *error = "decompressed size " + std::to_string(content) + " != expected " +
             std::to_string(expected_size);
    return false;
  }
  out->resize(expected_size);
  const size_t got = ZSTD_decompress(out->data(), out->size(), data, size);
  if (ZSTD_isError(got) || got != expected_size) {
    *error = std::string("corrupt zstd data: ") +
             (ZSTD_isError(got) ? ZSTD_getErrorName(got) : "short output");
    return false;
  }
  return true;
}

}  // namespace common
}  // namespace sarmap
