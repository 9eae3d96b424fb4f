#pragma once
// SlamNode: the LCM adapter of 2D graph SLAM. SCAN + ODOM in (each stream gated on its own
// clock, then through a time-ordered queue), POSE, MAP and SLAM_ANCHORS out;
// SLAM_ANCHOR_REQUEST selects the anchors (rate-limited per client and overall). Saves its
// state crash-safe and resumes from it (`resume`), or localises in a saved map (`load_map`).
// See README.md.

#include <memory>

#include "common/node.h"
#include "slam/slam.h"
#include "slam/slam_node_options.h"

namespace sarmap {
namespace slam {

class SlamNode {
 public:
  // Throws std::runtime_error for a map to localise in that cannot be loaded.
  SlamNode(const SlamNodeOptions& options, common::Node* node);
  ~SlamNode();

  // After the node stopped: applies what is still queued, optimises once more, publishes the
  // anchors, saves the state and writes the map (map_output_prefix).
  void Finish();

  const Slam& slam() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam
}  // namespace sarmap
