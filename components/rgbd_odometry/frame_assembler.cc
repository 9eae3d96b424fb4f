#include "rgbd_odometry/frame_assembler.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/image_codec.h"
#include "common/image_messages.h"

namespace sarmap {
namespace rgbd_odometry {

namespace {
constexpr size_t kMaxRecentColor = 10;
constexpr int64_t kRestartJumpUs = 1000000;  // depth time going back more: a restart
}  // namespace

FrameAssembler::FrameAssembler(bool need_color, double max_pair_dt_s, double color_wait_s,
                               int max_pending)
    : need_color_(need_color),
      max_pair_dt_us_(static_cast<int64_t>(std::llround(max_pair_dt_s * 1e6))),
      color_wait_us_(static_cast<int64_t>(std::llround(color_wait_s * 1e6))),
      max_pending_(static_cast<size_t>(std::max(1, max_pending))) {}

int64_t FrameAssembler::total_warnings() const {
  int64_t n = 0;
  for (const auto& w : warnings_) n += w.second;
  return n;
}

void FrameAssembler::Warn(const std::string& kind, const std::string& text) {
  ++warnings_[kind];
  last_warning_ = kind + ": " + text;
}

void FrameAssembler::AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready) {
  if (last_depth_utime_ != 0 && depth.header.utime <= last_depth_utime_) {
    if (last_depth_utime_ - depth.header.utime <= kRestartJumpUs) {
      Warn("depth_out_of_order", "depth at " + std::to_string(depth.header.utime) +
                                     " us is not after the previous one at " +
                                     std::to_string(last_depth_utime_) + " us");
      return;
    }
    // Time went far back: a log replayed again, a restarted source. Start over (keeping the
    // colour images that may belong to this depth).
    Warn("time_restart", "depth time went back from " + std::to_string(last_depth_utime_) + " to " +
                             std::to_string(depth.header.utime) + " us");
    pending_depth_.clear();
    const int64_t t = depth.header.utime;
    recent_color_.erase(std::remove_if(recent_color_.begin(), recent_color_.end(),
                                       [&](const sarmap::image_t& c) {
                                         return c.header.utime > t + color_wait_us_;
                                       }),
                        recent_color_.end());
    now_utime_ = t;
    for (const auto& c : recent_color_) now_utime_ = std::max(now_utime_, c.header.utime);
  }
  last_depth_utime_ = depth.header.utime;
  now_utime_ = std::max(now_utime_, depth.header.utime);
  if (!need_color_) {
    RgbdFrame frame;
    if (Build(depth, nullptr, &frame)) ready->push_back(std::move(frame));
    return;
  }
  pending_depth_.push_back(depth);
  while (pending_depth_.size() > max_pending_) {
    Warn("depth_backlog", "depth at " + std::to_string(pending_depth_.front().header.utime) +
                              " us dropped: no colour yet and newer depth waiting");
    pending_depth_.pop_front();
  }
  Release(ready);
}

void FrameAssembler::AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready) {
  if (!need_color_) return;
  now_utime_ = std::max(now_utime_, color.header.utime);
  recent_color_.push_back(color);
  while (recent_color_.size() > kMaxRecentColor) recent_color_.pop_front();
  Release(ready);
}

void FrameAssembler::Release(std::vector<RgbdFrame>* ready) {
  while (!pending_depth_.empty()) {
    const sarmap::image_t& depth = pending_depth_.front();
    const int64_t t = depth.header.utime;
    auto best = recent_color_.end();
    int64_t best_dt = 0;
    for (auto it = recent_color_.begin(); it != recent_color_.end(); ++it) {
      const int64_t dt = std::llabs(it->header.utime - t);
      if (dt <= max_pair_dt_us_ && (best == recent_color_.end() || dt < best_dt)) {
        best = it;
        best_dt = dt;
      }
    }
    if (best != recent_color_.end()) {
      RgbdFrame frame;
      if (Build(depth, &*best, &frame)) ready->push_back(std::move(frame));
      recent_color_.erase(recent_color_.begin(), best + 1);  // this one and older ones
      pending_depth_.pop_front();
      continue;
    }
    if (now_utime_ - t > color_wait_us_) {
      Warn("no_color", "depth at " + std::to_string(t) + " us has no colour image within " +
                           std::to_string(max_pair_dt_us_) + " us");
      pending_depth_.pop_front();
      continue;
    }
    break;  // wait for its colour
  }
}

bool FrameAssembler::Build(const sarmap::image_t& depth, const sarmap::image_t* color,
                           RgbdFrame* frame) {
  std::string error;
  if (depth.width <= 0 || depth.height <= 0 || depth.width > 8192 || depth.height > 8192) {
    Warn("depth_decode",
         "bad depth size " + std::to_string(depth.width) + "x" + std::to_string(depth.height));
    return false;
  }
  if (!common::DecodeDepthImage(depth, &frame->depth, &error)) {
    Warn("depth_decode", error);
    return false;
  }
  const auto& in = depth.intrinsics;
  if (!(std::isfinite(in.fx) && std::isfinite(in.fy) && in.fx > 0 && in.fy > 0 &&
        std::isfinite(in.cx) && std::isfinite(in.cy))) {
    Warn("bad_intrinsics", "depth at " + std::to_string(depth.header.utime) + " us has fx " +
                               std::to_string(in.fx) + " fy " + std::to_string(in.fy));
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
      Warn("color_size_mismatch",
           "colour " + std::to_string(color->width) + "x" + std::to_string(color->height) +
               " vs depth " + std::to_string(depth.width) + "x" + std::to_string(depth.height));
      return false;
    }
    if (!common::DecodeColorImage(*color, &frame->image, &error)) {
      Warn("color_decode", error);
      return false;
    }
    if (frame->image.size() != static_cast<size_t>(depth.width) * depth.height * 3) {
      Warn("color_decode", "decoded colour has " + std::to_string(frame->image.size()) +
                               " bytes, expected width*height*3");
      return false;
    }
    frame->image_channels = 3;
  }
  return true;
}

}  // namespace rgbd_odometry
}  // namespace sarmap
