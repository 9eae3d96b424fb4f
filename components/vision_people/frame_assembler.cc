#include "vision_people/frame_assembler.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/image_codec.h"
#include "common/image_messages.h"

namespace sarmap {
namespace vision_people {
namespace {
constexpr int kMaxSide = 8192;

std::string Size(const sarmap::image_t& im) {
  return std::to_string(im.width) + "x" + std::to_string(im.height);
}

common::DepthColorPairing Pairing(double max_pair_dt_s, double color_wait_s, bool require_color) {
  common::DepthColorPairing p;
  p.require_color = require_color;
  p.max_pair_dt_s = max_pair_dt_s;
  p.color_wait_s = color_wait_s;
  return p;
}
}  // namespace

FrameAssembler::FrameAssembler(double max_pair_dt_s, double color_wait_s, bool require_color)
    : FrameAssemblerBase(Pairing(max_pair_dt_s, color_wait_s, require_color)) {}

bool FrameAssembler::Build(const common::DepthColorPairer::Pair& pair, RgbdFrame* frame) {
  const sarmap::image_t& depth = pair.depth;
  const sarmap::image_t* color = pair.has_color ? &pair.color : nullptr;
  std::string error;
  if (depth.width <= 0 || depth.height <= 0 || depth.width > kMaxSide || depth.height > kMaxSide) {
    pairer_.Warn("depth_empty", "depth image of size " + Size(depth));
    return false;
  }
  if (!common::DecodeDepthImage(depth, &depth_buffer_, &error)) {
    pairer_.Warn("depth_decode", error);
    return false;
  }
  const auto& k = depth.intrinsics;
  PinholeIntrinsics intr;
  intr.fx = k.fx;
  intr.fy = k.fy;
  intr.cx = k.cx;
  intr.cy = k.cy;
  if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy)) ||
      k.fx <= 0 || k.fy <= 0) {
    pairer_.Warn("depth_intrinsics",
                 "depth image without valid intrinsics (fx " + std::to_string(k.fx) + ")");
    return false;
  }
  const double unit =
      depth.depth_unit_m > 0 && std::isfinite(depth.depth_unit_m) ? depth.depth_unit_m : 0.001;
  frame->utime = depth.header.utime;
  CloudFromDepth(depth_buffer_.data(), depth.width, depth.height, unit, intr, frame);
  frame->rgb.clear();
  if (color) {
    std::vector<uint8_t> rgb;
    if (color->width != depth.width || color->height != depth.height) {
      pairer_.Warn("color_size_mismatch",
                   "colour " + Size(*color) + " vs depth " + Size(depth) + "; using depth only");
    } else if (!common::DecodeColorImage(*color, &rgb, &error)) {
      pairer_.Warn("color_decode", error + "; using depth only");
    } else if (rgb.size() != static_cast<size_t>(depth.width) * depth.height * 3) {
      pairer_.Warn("color_size_mismatch",
                   "decoded colour has " + std::to_string(rgb.size()) + " bytes");
    } else {
      frame->rgb = std::move(rgb);
    }
  }
  return true;
}

void FrameAssembler::AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready) {
  if (depth.pixel_format != sarmap::image_t::PIXEL_DEPTH_U16) {
    pairer_.Warn("depth_format",
                 "DEPTH message with pixel format " + std::to_string(depth.pixel_format));
    return;
  }
  FrameAssemblerBase::AddDepth(depth, ready);
}

void FrameAssembler::AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready) {
  if (color.pixel_format == sarmap::image_t::PIXEL_DEPTH_U16) {
    pairer_.Warn("color_format", "RGB message carries a depth image");
    return;
  }
  FrameAssemblerBase::AddColor(color, ready);
}

}  // namespace vision_people
}  // namespace sarmap
