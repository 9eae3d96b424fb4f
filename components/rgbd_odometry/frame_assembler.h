#pragma once
// DEPTH and RGB image_t messages, paired by common::DepthColorPairer, decoded into RgbdFrames
// for RgbdOdometry. Only the generated message structs, no transport, so it is testable without
// a bus.
//
// need_color false (icp, fast_icp): every depth message becomes a frame at once, colour is
// ignored. need_color true (rgbd, rgbd_icp): a depth message needs its colour image (a depth
// image without one is dropped, "no_color"; beyond max_pending waiting, "depth_backlog"). The
// pairing rules, time restarts included, are the pairer's. Every bad input is counted under a
// named warning and skipped; nothing throws.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/depth_color_pairer.h"
#include "rgbd_odometry/rgbd_odometry.h"
#include "sarmap/image_t.hpp"

namespace sarmap {
namespace rgbd_odometry {

class FrameAssembler : public common::FrameAssemblerBase<RgbdFrame> {
 public:
  // Warnings: "depth_decode", "color_decode", "color_size_mismatch", "no_color",
  // "depth_backlog", "depth_out_of_order", "time_restart", "bad_intrinsics".
  FrameAssembler(bool need_color, double max_pair_dt_s, double color_wait_s, int max_pending = 3);

 private:
  bool Build(const common::DepthColorPairer::Pair& pair, RgbdFrame* frame) override;
};

}  // namespace rgbd_odometry
}  // namespace sarmap
