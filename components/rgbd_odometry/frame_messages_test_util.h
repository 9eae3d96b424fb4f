#pragma once
// The DEPTH and RGB messages of a rendered synthetic frame, as sarmap-depth publishes a camera's:
// for the node's in-process and multi-process tests.

#include <cstdint>
#include <vector>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "rgbd_odometry/synthetic_room.h"

namespace sarmap {
namespace rgbd_odometry {
namespace testing_util {

struct FrameMessages {
  image_t depth;
  image_t color;  // JPEG of the grey image as RGB
};

// `color_width` x `color_height` (0: the frame's size) crops the colour image from the top left,
// for a colour stream that does not match the depth.
inline FrameMessages FrameMessagesOf(const RgbdFrame& f, int64_t seq, int color_width = 0,
                                     int color_height = 0) {
  header_t h;
  h.utime = f.utime;
  h.seq = seq;
  h.frame = "camera";
  camera_intrinsics_t k{};
  k.width = f.width;
  k.height = f.height;
  k.fx = f.camera.fx, k.fy = f.camera.fy, k.cx = f.camera.cx, k.cy = f.camera.cy;
  const int cw = color_width > 0 ? color_width : f.width;
  const int ch = color_height > 0 ? color_height : f.height;
  std::vector<uint8_t> rgb(static_cast<size_t>(cw) * ch * 3);
  for (int v = 0; v < ch; ++v)
    for (int u = 0; u < cw; ++u)
      for (int c = 0; c < 3; ++c) rgb[(v * cw + u) * 3 + c] = f.image[v * f.width + u];
  camera_intrinsics_t ck = k;
  ck.width = cw;
  ck.height = ch;
  FrameMessages out;
  out.color = common::MakeColorImage(h, ck, rgb.data(), cw, ch, 90);
  out.depth = common::MakeDepthImage(h, k, f.depth.data(), f.width, f.height);
  return out;
}

}  // namespace testing_util
}  // namespace rgbd_odometry
}  // namespace sarmap
