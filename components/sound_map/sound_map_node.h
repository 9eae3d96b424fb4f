#pragma once
// SoundMapNode: the LCM adapter of the robot's sound map (Su 2017 §4.3).
//   in:  POSE (pose_t), SLAM_ANCHORS (slam_anchors_t), DOA_MAP (doa_t), PEOPLE_AUDIO
//        (people_detections_t), MAP (occupancy_grid_t: the mapped site, optional)
//   out: SLAM_ANCHOR_REQUEST (slam_anchor_request_t), SOUND_MAP (sound_map_t)
// Each input stream is gated on its own clock (common/stamp_gate.h), then SoundMapIntake applies
// the inputs in time order; results depend on message time only. The state is saved crash-safe
// and resumed after a restart (`resume`).

#include <memory>

#include "common/node.h"
#include "common/stamp_gate.h"
#include "common/time.h"
#include "sound_map/online_sound_map.h"
#include "sound_map/sound_map_intake.h"
#include "sound_map/sound_map_messages.h"

namespace sarmap {
namespace sound_map {

class SoundMapNode {
 public:
  SoundMapNode(const SoundMapNodeOptions& options, common::Node* node);

  // After the node stopped: what still waits in the queue (the last reorder delay of the
  // mission) is applied, and the final map published and saved.
  void Finish();

  const OnlineSoundMap& map() const { return *map_; }
  // Inputs dropped: stamped far from their stream's clock / older than what the queue applied.
  int64_t off_clock() const { return gates_.dropped(); }
  int64_t dropped_late() const { return intake_->dropped_late(); }

 private:
  enum Gate { kPoseGate = 0, kAnchorsGate = 1, kDoaGate = 2, kHeardGate = 3 };

  bool StampOk(Gate gate, common::Utime utime, const common::ReceiveInfo& info);
  void OnAnchors(const slam_anchors_t& m, const common::ReceiveInfo& info);
  void SaveState();
  void UpdateStatus();

  SoundMapNodeOptions options_;
  common::Node* node_;
  std::unique_ptr<OnlineSoundMap> map_;
  common::Node::Publisher<sound_map_t> map_pub_;
  common::Node::Publisher<slam_anchor_request_t> request_pub_;
  common::StampGates gates_;
  std::unique_ptr<SoundMapIntake> intake_;
  common::RateLimiter anchors_warning_{5.0}, save_warning_{30.0};
};

}  // namespace sound_map
}  // namespace sarmap
