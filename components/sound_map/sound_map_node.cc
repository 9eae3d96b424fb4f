#include "sound_map/sound_map_node.h"

#include <cmath>
#include <string>

#include "common/logging.h"
#include "common/robot_config.h"
#include "common/state_file.h"

namespace sarmap {
namespace sound_map {

SoundMapNode::SoundMapNode(const SoundMapNodeOptions& options, common::Node* node)
    : options_(options),
      node_(node),
      map_pub_(node->Advertise<sound_map_t>(options.sound_map_channel)),
      request_pub_(node->Advertise<slam_anchor_request_t>(options.anchor_request_channel)),
      gates_(options.stamp_gate) {
  const auto robot = common::LoadRobot(options_.robot_config);
  if (std::abs(robot.base_from_mic_array.roll_rad) > 1e-6 ||
      std::abs(robot.base_from_mic_array.pitch_rad) > 1e-6) {
    SARMAP_LOG(WARN) << "base_from_mic_array roll/pitch are ignored by the planar sound map";
  }
  map_ = std::make_unique<OnlineSoundMap>(options_.map, MountFromRobot(robot));
  if (options_.resume && !options_.state_file.empty()) {
    try {
      if (map_->Load(options_.state_file)) {
        SARMAP_LOG(INFO) << "resumed " << map_->ekf().source_ids().size() << " sources from "
                         << options_.state_file;
      }
    } catch (const std::exception& e) {  // one clear line and a clean start, no crash loop
      const std::string aside = common::SetAsideStateFile(options_.state_file);
      SARMAP_LOG(ERROR) << "not resumed, starting empty: " << common::EscapeForLog(e.what(), 512)
                        << (aside.empty() ? "" : " (moved to " + aside + ")");
    }
  }
  intake_ = std::make_unique<SoundMapIntake>(
      options_, map_.get(), [this](sound_map_t& m) { map_pub_.Publish(&m); },
      [this](slam_anchor_request_t& r) { request_pub_.Publish(&r); });

  node->Subscribe<pose_t>(
      options_.pose_channel,
      [this](const pose_t& m, const auto& info) {
        if (StampOk(kPoseGate, m.header.utime, info)) intake_->OnPose(m);
      },
      options_.input_queue_capacity);
  node->Subscribe<slam_anchors_t>(
      options_.anchors_channel,
      [this](const slam_anchors_t& m, const auto& info) { OnAnchors(m, info); });
  node->Subscribe<doa_t>(
      options_.doa_channel,
      [this](const doa_t& m, const auto& info) {
        if (StampOk(kDoaGate, m.header.utime, info)) intake_->OnDoa(m);
      },
      options_.input_queue_capacity);
  node->Subscribe<people_detections_t>(
      options_.people_audio_channel,
      [this](const people_detections_t& m, const auto& info) {
        if (StampOk(kHeardGate, m.header.utime, info)) intake_->OnHeard(m);
      },
      options_.input_queue_capacity);
  if (!options_.site_map_channel.empty()) {
    node->Subscribe<occupancy_grid_t>(
        options_.site_map_channel,
        [this](const occupancy_grid_t& m, const auto&) { intake_->OnSiteMap(m); });
  }
  if (options_.request_repeat_s > 0) {
    node->AddTimer(options_.request_repeat_s, [this] {
      if (!map_->AnchorNodeIds().empty()) intake_->SendRequest(intake_->newest_utime());
    });
  }
  if (!options_.state_file.empty())
    node->AddTimer(options_.state_save_period_s, [this] { SaveState(); });
  node->AddTimer(1.0, [this] { UpdateStatus(); });
}

// One far-future stamp must not become the queue's clock (every later input "late").
bool SoundMapNode::StampOk(Gate gate, common::Utime utime, const common::ReceiveInfo& info) {
  if (gates_.Accept(gate, utime, info.receive_time_s)) return true;
  node_->Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
  return false;
}

void SoundMapNode::OnAnchors(const slam_anchors_t& m, const common::ReceiveInfo& info) {
  if (!StampOk(kAnchorsGate, m.header.utime, info)) return;
  if (!intake_->OnAnchors(m) && anchors_warning_.Allow(common::SteadySeconds())) {
    SARMAP_LOG(WARN) << "SLAM_ANCHORS: covariance_dim " << m.covariance_dim << " != 3(1+"
                     << m.num_anchors << ") or rows missing, dropped";
  }
}

void SoundMapNode::SaveState() {
  if (options_.state_file.empty() || !intake_->changed()) return;
  intake_->clear_changed();
  try {
    map_->Save(options_.state_file);
  } catch (const std::exception& e) {
    if (save_warning_.Allow(common::SteadySeconds()))
      SARMAP_LOG(WARN) << "state not saved: " << common::EscapeForLog(e.what(), 512);
  }
}

void SoundMapNode::UpdateStatus() {
  const auto& c = map_->counters();
  node_->SetStatusMessage(
      "sources " + std::to_string(map_->ekf().source_ids().size()) + " (born " +
      std::to_string(c.doa_new_sources) + ", pruned " +
      std::to_string(c.sources_pruned + c.mirrors_pruned) + "), doa used " +
      std::to_string(c.doa_used) + ", gated " + std::to_string(c.doa_gated_out) + ", too steep " +
      std::to_string(c.doa_too_steep) + ", on path " + std::to_string(c.sources_on_path) +
      ", back-propagations " + std::to_string(c.back_propagations) + " (anchors skipped " +
      std::to_string(c.anchors_skipped) + "), late inputs " +
      std::to_string(intake_->dropped_late()) + ", off-clock stamps " +
      std::to_string(gates_.dropped()) + " (re-anchors " + std::to_string(gates_.reanchors()) +
      ")");
}

void SoundMapNode::Finish() {
  intake_->Finish();
  SaveState();
}

}  // namespace sound_map
}  // namespace sarmap
