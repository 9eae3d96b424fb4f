#include "people_map/people_map_node.h"

#include <algorithm>
#include <string>

#include "common/logging.h"
#include "common/robot_config.h"
#include "common/state_file.h"

namespace sarmap {
namespace people_map {

PeopleMapNode::PeopleMapNode(const PeopleMapNodeOptions& options, common::Node* node)
    : options_(options),
      node_(node),
      map_(options.map),
      publisher_(node->Advertise<people_map_t>(options.output_channel)),
      request_pub_(node->Advertise<slam_anchor_request_t>(options.anchor_request_channel)),
      gates_(options.stamp_gate) {
  const common::RobotOptions robot = common::LoadRobot(options_.robot_config);
  if (!options_.state_file.empty()) {
    // A corrupt state file must not make the node crash-loop: one clear line, a clean start.
    try {
      if (map_.Load(options_.state_file)) {
        SARMAP_LOG(INFO) << "resumed " << map_.people().size() << " people from "
                         << options_.state_file;
      }
    } catch (const std::exception& e) {
      const std::string aside = common::SetAsideStateFile(options_.state_file);
      SARMAP_LOG(ERROR) << "not resumed, starting with an empty people map: "
                        << common::EscapeForLog(e.what(), 512)
                        << (aside.empty() ? "" : " (moved to " + aside + ")");
    }
  }
  intake_ = std::make_unique<PeopleMapIntake>(
      options_, robot.base_from_camera.ToRigid3d(), robot.base_from_mic_array.ToRigid3d(), &map_,
      [this](common::Utime utime) { Publish(utime); },
      [this](slam_anchor_request_t& r) { request_pub_.Publish(&r); });
  // After a restart from saved state, the people already found are published at once (at the
  // time of their last detection), not only after the next detection: the operator and the
  // recorder never see the map lose them.
  common::Utime latest_utime = 0;
  for (const auto& [id, person] : map_.people())
    latest_utime = std::max(latest_utime, person.last_detected_utime);
  intake_->set_latest_utime(latest_utime);

  node->Subscribe<pose_t>(
      options_.pose_channel,
      [this](const pose_t& m, const auto& info) {
        if (StampOk(kPoseGate, m.header.utime, info)) intake_->OnPose(m);
      },
      options_.input_queue_capacity);
  node->Subscribe<people_detections_t>(
      options_.visual_channel,
      [this](const people_detections_t& m, const auto& info) {
        if (StampOk(kSeenGate, m.header.utime, info)) intake_->OnSeen(m);
      },
      options_.input_queue_capacity);
  node->Subscribe<people_detections_t>(
      options_.audio_channel,
      [this](const people_detections_t& m, const auto& info) {
        if (StampOk(kHeardGate, m.header.utime, info)) intake_->OnHeard(m);
      },
      options_.input_queue_capacity);
  node->Subscribe<sound_map_t>(options_.sound_map_channel,
                               [this](const sound_map_t& m, const auto& info) {
                                 if (StampOk(kSoundMapGate, m.header.utime, info))
                                   intake_->OnSoundMap(m);
                               });
  node->Subscribe<slam_anchors_t>(options_.anchors_channel,
                                  [this](const slam_anchors_t& m, const auto& info) {
                                    if (!StampOk(kAnchorsGate, m.header.utime, info)) return;
                                    if (!intake_->OnAnchors(m))
                                      node_->Reject(info.channel, "a node pose is not finite");
                                  });
  // SLAM forgets a client that stays silent (anchor_client_timeout_s): the request is repeated.
  if (options_.request_repeat_s > 0) {
    node->AddTimer(options_.request_repeat_s, [this] {
      if (!map_.AnchorNodeIds().empty()) intake_->SendRequest(intake_->latest_utime());
    });
  }
  node->AddTimer(options_.publish_period_s, [this] { OnTimer(); });
  node->AddTimer(options_.save_period_s, [this] { Save(); });
}

// One far-future stamp must not move the pose history or the queue's clock.
bool PeopleMapNode::StampOk(Gate gate, common::Utime utime, const common::ReceiveInfo& info) {
  if (gates_.Accept(gate, utime, info.receive_time_s)) return true;
  node_->Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
  return false;
}

void PeopleMapNode::Publish(common::Utime utime) {
  auto msg = PeopleMapMessage(map_.Report(utime), utime);
  publisher_.Publish(&msg);
}

void PeopleMapNode::OnTimer() {
  intake_->Release();
  if (intake_->latest_utime() > 0) Publish(intake_->latest_utime());
  node_->SetStatusMessage(std::to_string(map_.people().size()) + " people, " +
                          std::to_string(intake_->without_pose()) + " detections without pose, " +
                          std::to_string(intake_->dropped_late()) + " late, " +
                          std::to_string(gates_.dropped()) + " off-clock stamps (" +
                          std::to_string(gates_.reanchors()) + " re-anchors), " +
                          std::to_string(intake_->slam_restarts()) + " SLAM restarts");
}

void PeopleMapNode::Save() {
  if (options_.state_file.empty() || !intake_->dirty()) return;
  try {
    map_.Save(options_.state_file);
    intake_->clear_dirty();
  } catch (const std::exception& e) {
    SARMAP_LOG(ERROR) << common::EscapeForLog(e.what(), 512);  // may quote a keyword
  }
}

void PeopleMapNode::Finish() {
  intake_->Finish();
  if (intake_->latest_utime() > 0) Publish(intake_->latest_utime());
  Save();
}

}  // namespace people_map
}  // namespace sarmap
