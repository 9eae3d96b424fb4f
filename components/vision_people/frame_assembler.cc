#include "vision_people/frame_assembler.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/image_codec.h"
#include "common/image_messages.h"

namespace sarmap {
namespace vision_people {
namespace {
constexpr size_t kMaxPending = 8;  // frames kept waiting for a partner
constexpr int kMaxSide = 8192;

std::string Size(const sarmap::image_t& im) {
  return std::to_string(im.width) + "x" + std::to_string(im.height);
}
}  // namespace

FrameAssembler::FrameAssembler(double max_pair_dt_s, double color_wait_s, bool require_color)
    : max_pair_dt_us_(static_cast<int64_t>(max_pair_dt_s * 1e6)),
      color_wait_us_(static_cast<int64_t>(color_wait_s * 1e6)),
      require_color_(require_color) {}

int64_t FrameAssembler::total_warnings() const {
  int64_t n = 0;
  for (const auto& w : warnings_) n += w.second;
  return n;
}

void FrameAssembler::Warn(const std::string& kind, const std::string& text) {
  ++warnings_[kind];
  last_warning_ = kind + ": " + text;
}

bool FrameAssembler::Build(const sarmap::image_t& depth, const sarmap::image_t* color,
                           RgbdFrame* frame) {
  std::string error;
  if (depth.width <= 0 || depth.height <= 0 || depth.width > kMaxSide || depth.height > kMaxSide) {
    Warn("depth_empty", "depth image of size " + Size(depth));
    return false;
  }
  if (!common::DecodeDepthImage(depth, &depth_buffer_, &error)) {
    Warn("depth_decode", error);
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
    Warn("depth_intrinsics",
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
      Warn("color_size_mismatch",
           "colour " + Size(*color) + " vs depth " + Size(depth) + "; using depth only");
    } else if (!common::DecodeColorImage(*color, &rgb, &error)) {
      Warn("color_decode", error + "; using depth only");
    } else if (rgb.size() != static_cast<size_t>(depth.width) * depth.height * 3) {
      Warn("color_size_mismatch", "decoded colour has " + std::to_string(rgb.size()) + " bytes");
    } else {
      frame->rgb = std::move(rgb);
    }
  }
  return true;
}

void FrameAssembler::Flush(std::vector<RgbdFrame>* ready) {
  if (pending_depth_.empty()) return;
  Release(pending_depth_.back().header.utime + color_wait_us_ + 1, ready);
}

void FrameAssembler::Release(int64_t now_utime, std::vector<RgbdFrame>* ready) {
  // Pair pending depth frames with colour; give up on those that waited long enough.
  while (!pending_depth_.empty()) {
    const sarmap::image_t& d = pending_depth_.front();
    const sarmap::image_t* best = nullptr;
    int64_t best_dt = max_pair_dt_us_ + 1;
    for (const auto& c : recent_color_) {
      const int64_t dt = std::llabs(c.header.utime - d.header.utime);
      if (dt < best_dt) {
        best_dt = dt;
        best = &c;
      }
    }
    const bool timed_out =
        now_utime - d.header.utime > color_wait_us_ || pending_depth_.size() > kMaxPending;
    if (!best && !timed_out) break;
    if (!best) {
      if (require_color_) {
        Warn("no_color",
             "depth frame at " + std::to_string(d.header.utime) + " has no colour; dropped");
        pending_depth_.pop_front();
        continue;
      }
      Warn("no_color",
           "depth frame at " + std::to_string(d.header.utime) + " has no colour; depth only");
    }
    RgbdFrame frame;
    if (Build(d, best, &frame)) ready->push_back(std::move(frame));
    pending_depth_.pop_front();
  }
  // Colour older than anything we could still pair is dropped.
  const int64_t oldest = pending_depth_.empty() ? now_utime : pending_depth_.front().header.utime;
  while (!recent_color_.empty() &&
         (recent_color_.front().header.utime < oldest - max_pair_dt_us_ - color_wait_us_ ||
          recent_color_.size() > kMaxPending)) {
    recent_color_.pop_front();
  }
}

void FrameAssembler::AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready) {
  if (depth.pixel_format != sarmap::image_t::PIXEL_DEPTH_U16) {
    Warn("depth_format", "DEPTH message with pixel format " + std::to_string(depth.pixel_format));
    return;
  }
  if (!pending_depth_.empty() && depth.header.utime <= pending_depth_.back().header.utime) {
    Warn("depth_out_of_order",
         "depth frame at " + std::to_string(depth.header.utime) + " is not newer");
    return;
  }
  pending_depth_.push_back(depth);
  Release(depth.header.utime, ready);
}

void FrameAssembler::AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready) {
  if (color.pixel_format == sarmap::image_t::PIXEL_DEPTH_U16) {
    Warn("color_format", "RGB message carries a depth image");
    return;
  }
  auto pos =
      std::upper_bound(recent_color_.begin(), recent_color_.end(), color.header.utime,
                       [](int64_t t, const sarmap::image_t& c) { return t < c.header.utime; });
  recent_color_.insert(pos, color);
  Release(color.header.utime, ready);
}

}  // namespace vision_people
}  // namespace sarmap
