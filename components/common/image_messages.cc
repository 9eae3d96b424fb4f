#include "common/image_messages.h"

#include <cstring>

#include "common/compression.h"

namespace sarmap {
namespace common {

sarmap::image_t MakeDepthImage(const sarmap::header_t& header,
                               const sarmap::camera_intrinsics_t& intrinsics,
                               const uint16_t* depth_mm, int width, int height, bool compress) {
  sarmap::image_t image;
  image.header = header;
  image.intrinsics = intrinsics;
  image.width = width;
  image.height = height;
  image.pixel_format = sarmap::image_t::PIXEL_DEPTH_U16;
  image.depth_unit_m = 0.001;
  if (compress) {
    image.compression = sarmap::image_t::COMPRESSION_DEPTH_DELTA_ZSTD;
    image.data = CompressDepth(depth_mm, width, height);
  } else {
    image.compression = sarmap::image_t::COMPRESSION_NONE;
    image.data.resize(static_cast<size_t>(width) * height * 2);
    memcpy(image.data.data(), depth_mm, image.data.size());
  }
  image.size = static_cast<int32_t>(image.data.size());
  return image;
}

bool DecodeDepthImage(const sarmap::image_t& image, std::vector<uint16_t>* depth,
                      std::string* error) {
  if (image.pixel_format != sarmap::image_t::PIXEL_DEPTH_U16) {
    *error = "not a depth image";
    return false;
  }
  if (image.width <= 0 || image.height <= 0 || image.data.size() != static_cast<size_t>(image.size)) {
    *error = "bad depth image header";
    return false;
  }
  const size_t n = static_cast<size_t>(image.width) * image.height;
  depth->resize(n);
  switch (image.compression) {
    case sarmap::image_t::COMPRESSION_NONE:
      if (image.data.size() != 2 * n) {
        *error = "uncompressed depth of wrong size";
        return false;
      }
      memcpy(depth->data(), image.data.data(), 2 * n);
      return true;
    case sarmap::image_t::COMPRESSION_DEPTH_DELTA_ZSTD:
      return DecompressDepth(image.data.data(), image.data.size(), image.width, image.height,
                             depth->data(), error);
    default:
      *error = "unsupported depth compression " + std::to_string(image.compression);
      return false;
  }
}

bool DecodeOccupancyGrid(const sarmap::occupancy_grid_t& grid, std::vector<int8_t>* cells,
                         std::string* error) {
  if (grid.width <= 0 || grid.height <= 0) {
    *error = "bad grid size";
    return false;
  }
  const size_t n = static_cast<size_t>(grid.width) * grid.height;
  std::vector<uint8_t> bytes;
  if (grid.compression == sarmap::occupancy_grid_t::COMPRESSION_ZSTD) {
    if (!DecompressBytes(grid.data.data(), grid.data.size(), n, &bytes, error)) return false;
  } else if (grid.data.size() == n) {
    bytes = grid.data;
  } else {
    *error = "grid data of wrong size";
    return false;
  }
  cells->assign(bytes.begin(), bytes.end());
  return true;
}

}  // namespace common
}  // namespace sarmap
