#pragma once
// Pairs DEPTH and RGB image_t messages by utime and decodes them into RgbdFrames. No LCM
// transport here (only the generated message structs), so it is testable without a bus.
//
// A depth frame is paired with the colour image closest in time within max_pair_dt_s. A
// depth frame without colour waits until message time has moved color_wait_s past it, then
// goes on depth-only (unless require_color). Every bad or mismatched input is counted under a
// named warning and skipped or degraded; nothing throws.

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "sarmap/image_t.hpp"
#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

class FrameAssembler {
 public:
  FrameAssembler(double max_pair_dt_s, double color_wait_s, bool require_color);

  // Each call may complete frames; they are appended to `ready` in time order.
  void AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready);
  void AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready);

  // No more messages are coming for now (the bus went quiet): depth frames still waiting for
  // their colour go on as if the wait had timed out (the last frame of a depth-only replay).
  void Flush(std::vector<RgbdFrame>* ready);
  bool has_pending() const { return !pending_depth_.empty(); }

  // Warning name -> count (e.g. "depth_decode", "color_size_mismatch", "no_color").
  const std::map<std::string, int64_t>& warnings() const { return warnings_; }
  int64_t total_warnings() const;
  // The last warning's text, for logs.
  const std::string& last_warning() const { return last_warning_; }

 private:
  void Warn(const std::string& kind, const std::string& text);
  void Release(int64_t now_utime, std::vector<RgbdFrame>* ready);
  bool Build(const sarmap::image_t& depth, const sarmap::image_t* color, RgbdFrame* frame);

  int64_t max_pair_dt_us_;
  int64_t color_wait_us_;
  bool require_color_;
  std::deque<sarmap::image_t> pending_depth_;
  std::deque<sarmap::image_t> recent_color_;
  std::map<std::string, int64_t> warnings_;
  std::string last_warning_;
  std::vector<uint16_t> depth_buffer_;
};

}  // namespace vision_people
}  // namespace sarmap
