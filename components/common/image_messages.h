#pragma once
// Building and reading image_t messages. Depth (16-bit, lossless) lives here; colour (JPEG,
// through OpenCV) is in image_codec.h so that only the processes that need OpenCV link it.

#include <cstdint>
#include <string>
#include <vector>

#include "sarmap/image_t.hpp"

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

}  // namespace common
}  // namespace sarmap
