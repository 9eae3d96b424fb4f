#pragma once
// HandheldSoundMapNode: the LCM adapter of the linear-array sound map of Su 2017 ch. 5, for a
// hand-held rig whose 6-DoF pose comes from RGB-D odometry (sarmap-rgbd-odometry).
//   in:  RIG_POSE (pose_t), DOA_MAP (doa_t, KIND_ANGLE_1D), PEOPLE_AUDIO (people_detections_t)
//   out: SOUND_MAP (sound_map_t)
// Each input stream is gated on its own clock (common/stamp_gate.h), then applied through a
// time-ordered queue; results depend on message time only.

#include <Eigen/Geometry>
#include <functional>

#include "common/logging.h"
#include "common/node.h"
#include "common/stamp_gate.h"
#include "common/time.h"
#include "handheld_sound_map/handheld_sound_map_messages.h"
#include "handheld_sound_map/linear_array_map.h"

namespace sarmap {
namespace sound_map {

class HandheldSoundMapNode {
 public:
  HandheldSoundMapNode(const HandheldSoundMapOptions& options, common::Node* node);

  // After the node stopped: the last reorder_delay_s of inputs, one optimisation over
  // everything, and the final map published.
  void Finish();

  const LinearArraySoundMap& map() const { return map_; }
  int64_t bad_poses() const { return bad_poses_; }
  int64_t other_kinds() const { return other_kinds_; }

 private:
  enum Gate { kPoseGate = 0, kDoaGate = 1, kHeardGate = 2 };
  using Apply = std::function<void(common::Utime)>;

  bool StampOk(Gate gate, common::Utime utime, const common::ReceiveInfo& info);
  void Push(common::Utime utime, Apply apply);
  // Applies one input released by the queue; SOUND_MAP every publish_period_s of message time.
  void ApplyInput(common::Utime utime, Apply& apply);
  void PublishMap(common::Utime utime);
  void OnPose(const pose_t& m);
  void OnDoa(const doa_t& m);
  void UpdateStatus();

  HandheldSoundMapOptions options_;
  common::Node* node_;
  Eigen::Isometry3d rig_from_sensor_;
  LinearArraySoundMap map_;
  common::Node::Publisher<sound_map_t> map_pub_;
  common::TimeOrderedQueue<Apply> queue_;
  common::StampGates gates_;
  common::Utime last_publish_ = INT64_MIN / 2, newest_ = 0;
  int64_t bad_poses_ = 0, other_kinds_ = 0, warned_kinds_ = 0;
  common::RateLimiter pose_warning_{10.0}, kind_warning_{10.0};
};

}  // namespace sound_map
}  // namespace sarmap
