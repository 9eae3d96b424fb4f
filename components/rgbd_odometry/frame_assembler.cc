#include "rgbd_odometry/frame_assembler.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/image_codec.h"
#include "common/image_messages.h"

namespace sarmap {
namespace rgbd_odometry {

namespace {
common::DepthColorPairing Pairing(bool need_color, double max_pair_dt_s, double color_wait_s,
                                  int max_pending) {
  common::DepthColorPairing p;
  p.use_color = need_color;
  p.require_color = true;
  p.max_pair_dt_s = max_pair_dt_s;
  p.color_wait_s = color_wait_s;
  p.max_pending = max_pending;
  return p;
}
}  // namespace

FrameAssembler::FrameAssembler(bool need_color, double max_pair_dt_s, double color_wait_s,
                               int max_pending)
    : FrameAssemblerBase(Pairing(need_color, max_pair_dt_s, color_wait_s, max_pending)) {}

bool FrameAssembler::Build(const common::DepthColorPairer::Pair& pair, RgbdFrame* frame) {
  const sarmap::image_t& depth = pair.depth;
  const sarmap::image_t* color = pair.has_color ? &pair.color : nullptr;
  std::string error;
  if (depth.width <= 0 || depth.height <= 0 || depth.width > 8192 || depth.height > 8192) {
    pairer_.Warn("depth_decode", "bad depth size " + std::to_string(depth.width) + "x" +
                                     std::to_string(depth.height));
    return false;
  }
  if (!common::DecodeDepthImage(depth, &frame->depth, &error)) {
    pairer_.Warn("depth_decode", error);
    return false;
  }
  const auto& in = depth.intrinsics;
  if (!(std::isfinite(in.fx) && std::isfinite(in.fy) && in.fx > 0 && in.fy > 0 &&
        std::isfinite(in.cx) && std::isfinite(in.cy))) {
    pairer_.Warn("bad_intrinsics", "depth at " + std::to_string(depth.header.utime) +
                                       " us has fx " + std::to_string(in.fx) + " fy " +
                                       std::to_string(in.fy));
    return false;
  }
  frame->utime = depth.header.utime;
  frame->width = depth.width;
  frame->height = depth.height;
  frame->depth_unit_m = depth.depth_unit_m;
  frame->camera = {in.fx, in.fy, in.cx, in.cy};
  frame->image.clear();
  frame->image_channels = 0;
  if (color) {
    if (color->width != depth.width || color->height != depth.height) {
      pairer_.Warn("color_size_mismatch", "colour " + std::to_string(color->width) + "x" +
                                              std::to_string(color->height) + " vs depth " +
                                              std::to_string(depth.width) + "x" +
                                              std::to_string(depth.height));
      return false;
    }
    if (!common::DecodeColorImage(*color, &frame->image, &error)) {
      pairer_.Warn("color_decode", error);
      return false;
    }
    if (frame->image.size() != static_cast<size_t>(depth.width) * depth.height * 3) {
      pairer_.Warn("color_decode", "decoded colour has " + std::to_string(frame->image.size()) +
                                       " bytes, expected width*height*3");
      return false;
    }
    frame->image_channels = 3;
  }
  return true;
}

}  // namespace rgbd_odometry
}  // namespace sarmap
