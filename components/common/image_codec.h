#pragma once
// Colour image_t messages: JPEG (default) or raw RGB8, through OpenCV. Link
// sarmap_image_codec; the OpenCV headers stay in image_codec.cc.

#include <cstdint>
#include <string>
#include <vector>

#include "sarmap/image_t.hpp"

namespace sarmap {
namespace common {

// `rgb`: width*height*3 bytes, RGB order. jpeg_quality 1..100 compresses; 0 sends raw RGB8.
sarmap::image_t MakeColorImage(const sarmap::header_t& header,
                               const sarmap::camera_intrinsics_t& intrinsics, const uint8_t* rgb,
                               int width, int height, int jpeg_quality = 85);
// Decodes a colour image_t (raw RGB8/BGR8/GRAY8, JPEG or PNG) into RGB8.
bool DecodeColorImage(const sarmap::image_t& image, std::vector<uint8_t>* rgb, std::string* error);

}  // namespace common
}  // namespace sarmap
