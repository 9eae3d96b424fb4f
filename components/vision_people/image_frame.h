#pragma once
// Reads a depth image (16-bit PNG/PGM/TIFF) and its colour image into an RgbdFrame, for
// tests, the benchmark and the offline tool. OpenCV only in image_frame.cc.

#include <string>

#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

// The colour image beside a depth image, by the common RGB-D folder layouts: `depth` ->
// `color` / `rgb` (DIR/depth/1.pgm -> DIR/color/1.png, x_depth.tiff -> x_rgb.tiff) and
// `dep_` -> `img_`, with the same or a .png extension. Empty when none exists.
std::string FindColorImage(const std::string& depth_path);

// False with `error` set when the depth image cannot be read or is not 16-bit (an 8-bit
// depth image has lost its range). `unit_m`: metres per stored unit (millimetre PNG 0.001,
// TUM 0.0002). `color_path` empty: no colour; a colour image of another size is an error.
bool LoadDepthImageFrame(const std::string& depth_path, const std::string& color_path,
                         double unit_m, const PinholeIntrinsics& intrinsics, RgbdFrame* frame,
                         std::string* error);

}  // namespace vision_people
}  // namespace sarmap
