#pragma once
// DEPTH and RGB image_t messages, paired by common::DepthColorPairer, decoded into RgbdFrames
// (point clouds). No LCM transport here (only the generated message structs), so it is testable
// without a bus.
//
// A depth frame without colour goes on depth-only once its wait is over (unless
// require_color); colour that does not match the depth image (size, decoding) is counted and
// the frame goes on depth-only. Every bad or mismatched input is counted under a named warning
// and skipped or degraded; nothing throws.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/depth_color_pairer.h"
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
  bool has_pending() const { return pairer_.has_pending(); }

  // Warning name -> count (e.g. "depth_decode", "color_size_mismatch", "no_color").
  const std::map<std::string, int64_t>& warnings() const { return pairer_.warnings(); }
  int64_t total_warnings() const { return pairer_.total_warnings(); }
  // The last warning's text, for logs.
  const std::string& last_warning() const { return pairer_.last_warning(); }

 private:
  void BuildAll(std::vector<RgbdFrame>* ready);
  bool Build(const common::DepthColorPairer::Pair& pair, RgbdFrame* frame);

  common::DepthColorPairer pairer_;
  std::vector<common::DepthColorPairer::Pair> pairs_;
  std::vector<uint16_t> depth_buffer_;
};

}  // namespace vision_people
}  // namespace sarmap
