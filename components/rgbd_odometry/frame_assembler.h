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

class FrameAssembler {
 public:
  FrameAssembler(bool need_color, double max_pair_dt_s, double color_wait_s, int max_pending = 3);

  // Each call may complete frames; they are appended to `ready` in time order.
  void AddDepth(const sarmap::image_t& depth, std::vector<RgbdFrame>* ready);
  void AddColor(const sarmap::image_t& color, std::vector<RgbdFrame>* ready);

  // Warning name -> count ("depth_decode", "color_decode", "color_size_mismatch", "no_color",
  // "depth_backlog", "depth_out_of_order", "time_restart", "bad_intrinsics").
  const std::map<std::string, int64_t>& warnings() const { return pairer_.warnings(); }
  int64_t total_warnings() const { return pairer_.total_warnings(); }
  const std::string& last_warning() const { return pairer_.last_warning(); }

 private:
  void BuildAll(std::vector<RgbdFrame>* ready);
  bool Build(const common::DepthColorPairer::Pair& pair, RgbdFrame* frame);

  common::DepthColorPairer pairer_;
  std::vector<common::DepthColorPairer::Pair> pairs_;
};

}  // namespace rgbd_odometry
}  // namespace sarmap
