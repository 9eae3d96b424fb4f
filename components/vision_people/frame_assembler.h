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

class FrameAssembler : public common::FrameAssemblerBase<RgbdFrame> {
 public:
  // Warnings: e.g. "depth_decode", "color_size_mismatch", "no_color".
  FrameAssembler(double max_pair_dt_s, double color_wait_s, bool require_color);

  // As FrameAssemblerBase's, after refusing (and counting) a message of the other kind of image.
  void AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready);
  void AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready);

 private:
  bool Build(const common::DepthColorPairer::Pair& pair, RgbdFrame* frame) override;

  std::vector<uint16_t> depth_buffer_;
};

}  // namespace vision_people
}  // namespace sarmap
