#pragma once
// Building and reading image_t messages. Depth (16-bit, lossless) lives here; colour (JPEG,
// through OpenCV) is in image_codec.h so that only the processes that need OpenCV link it.

#include <cstdint>
#include <string>
#include <vector>

#include "common/compression.h"
#include "common/grid_geometry.h"
#include "sarmap/image_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"

namespace sarmap {
namespace common {

// A depth image in millimetres (0 = no reading), compressed losslessly unless `compress` is
// false.
sarmap::image_t MakeDepthImage(const sarmap::header_t& header,
                               const sarmap::camera_intrinsics_t& intrinsics,
                               const uint16_t* depth_mm, int width, int height,
                               bool compress = true);
// Decodes any depth image_t into width*height values in depth units; false with `error` set
// on a malformed image.
bool DecodeDepthImage(const sarmap::image_t& image, std::vector<uint16_t>* depth,
                      std::string* error);

// The occupancy grid message of a map: any type with resolution_m, width, height, origin_x_m,
// origin_y_m and row-major int8 cells (-1 unknown, 0..100), zstd-compressed when `compress`.
template <class Map>
sarmap::occupancy_grid_t MakeOccupancyGrid(const sarmap::header_t& header, const Map& map,
                                           bool compress) {
  sarmap::occupancy_grid_t grid{};
  grid.header = header;
  CopyGridGeometry(map, &grid);
  grid.origin_yaw_rad = 0;
  if (compress) {
    const std::vector<uint8_t> packed =
        CompressBytes(reinterpret_cast<const uint8_t*>(map.cells.data()), map.cells.size());
    grid.compression = sarmap::occupancy_grid_t::COMPRESSION_ZSTD;
    grid.data.assign(packed.begin(), packed.end());
  } else {
    grid.compression = sarmap::occupancy_grid_t::COMPRESSION_NONE;
    grid.data.assign(map.cells.begin(), map.cells.end());
  }
  grid.size = static_cast<int32_t>(grid.data.size());
  return grid;
}

// The cells of an occupancy grid (-1 unknown, 0..100), decompressed when needed; false with
// `error` set when the data does not match the grid's size.
bool DecodeOccupancyGrid(const sarmap::occupancy_grid_t& grid, std::vector<int8_t>* cells,
                         std::string* error);

}  // namespace common
}  // namespace sarmap
