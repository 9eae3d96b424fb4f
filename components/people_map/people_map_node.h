#pragma once
// PeopleMapNode: the LCM adapter of the people map. PEOPLE_VISUAL, PEOPLE_AUDIO, SOUND_MAP,
// SLAM_ANCHORS and POSE in; PEOPLE_MAP and SLAM_ANCHOR_REQUEST out. Each input stream is gated on
// its own clock (common/stamp_gate.h), then PeopleMapIntake applies the inputs in capture-time
// order with the robot pose interpolated at each detection's capture time, so replaying a log gives
// the same people map every time. The state is saved crash-safe and resumed after a restart.

#include <memory>

#include "common/node.h"
#include "common/stamp_gate.h"
#include "common/time.h"
#include "people_map/people_map.h"
#include "people_map/people_map_intake.h"

namespace sarmap {
namespace people_map {

class PeopleMapNode {
 public:
  // Loads the robot description and resumes from options.state_file when it holds a map (a
  // corrupt file is set aside with one log line and the map starts empty).
  PeopleMapNode(const PeopleMapNodeOptions& options, common::Node* node);

  // After the node stopped: applies what is still queued, publishes and saves once more.
  void Finish();

  const PeopleMap& map() const { return map_; }
  // For replay tools: the map (to trace what each detection did) and the intake's counters.
  PeopleMap* mutable_map() { return &map_; }
  const PeopleMapIntake& intake() const { return *intake_; }

 private:
  enum Gate { kPoseGate = 0, kSeenGate = 1, kHeardGate = 2, kSoundMapGate = 3, kAnchorsGate = 4 };

  bool StampOk(Gate gate, common::Utime utime, const common::ReceiveInfo& info);
  void Publish(common::Utime utime);
  void OnTimer();
  void Save();

  PeopleMapNodeOptions options_;
  common::Node* node_;
  PeopleMap map_;
  common::Node::Publisher<people_map_t> publisher_;
  common::Node::Publisher<slam_anchor_request_t> request_pub_;
  common::StampGates gates_;
  std::unique_ptr<PeopleMapIntake> intake_;
};

}  // namespace people_map
}  // namespace sarmap
