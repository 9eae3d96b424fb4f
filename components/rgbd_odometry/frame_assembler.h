#pragma once
// Pairs DEPTH and RGB image_t messages by utime and decodes them into RgbdFrames for
// RgbdOdometry. Only the generated message structs, no transport, so it is testable without a
// bus.
//
// need_color false (icp, fast_icp): every depth message becomes a frame at once, colour is
// ignored. need_color true (rgbd, rgbd_icp): a depth message is paired with the colour image
// closest in time within max_pair_dt_s; it waits until message time (the newest utime seen on
// either channel) has moved color_wait_s past it, then is dropped ("no_color"). At most
// max_pending depth messages wait; older ones are dropped ("depth_backlog"). Depth older than
// the previous depth is dropped ("depth_out_of_order"), unless it is more than 1 s older: then
// time restarted (a log replayed again) and pairing starts over ("time_restart"). Every bad
// input is counted under a named warning and skipped; nothing throws.

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "rgbd_odometry/rgbd_odometry.h"
#include "sarmap/image_t.hpp"

namespace sarmap {
namespace rgbd_odometry {

class FrameAssembler {
 public:
  FrameAssembler(bool need_color, double max_pair_dt_s, double color_wait_s, int max_pending = 3);

  // Each call may complete frames; they are appended to `ready` in time order.
  void AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready);
  void AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready);

  // Warning name -> count ("depth_decode", "color_decode", "color_size_mismatch", "no_color",
  // "depth_backlog", "depth_out_of_order", "time_restart", "bad_intrinsics").
  const std::map<std::string, int64_t>& warnings() const { return warnings_; }
  int64_t total_warnings() const;
  const std::string& last_warning() const { return last_warning_; }

 private:
  void Warn(const std::string& kind, const std::string& text);
  void Release(std::vector<RgbdFrame>* ready);
  bool Build(const sarmap::image_t& depth, const sarmap::image_t* color, RgbdFrame* frame);

  bool need_color_;
  int64_t max_pair_dt_us_;
  int64_t color_wait_us_;
  size_t max_pending_;
  int64_t now_utime_ = 0;
  int64_t last_depth_utime_ = 0;
  std::deque<sarmap::image_t> pending_depth_;
  std::deque<sarmap::image_t> recent_color_;
  std::map<std::string, int64_t> warnings_;
  std::string last_warning_;
};

}  // namespace rgbd_odometry
}  // namespace sarmap
