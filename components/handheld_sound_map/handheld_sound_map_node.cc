#include "handheld_sound_map/handheld_sound_map_node.h"

#include <algorithm>
#include <string>

namespace sarmap {
namespace sound_map {

HandheldSoundMapNode::HandheldSoundMapNode(const HandheldSoundMapOptions& options,
                                           common::Node* node)
    : options_(options),
      node_(node),
      rig_from_sensor_(RigFromSensor(options.rig_from_mic_array)),
      map_(options.map),
      map_pub_(node->Advertise<sound_map_t>(options.sound_map_channel)),
      queue_(common::SecondsToUtime(options.reorder_delay_s)),
      gates_(options.stamp_gate) {
  node->Subscribe<pose_t>(options_.pose_channel, [this](const pose_t& m, const auto& info) {
    if (StampOk(kPoseGate, m.header.utime, info)) OnPose(m);
  });
  node->Subscribe<doa_t>(options_.doa_channel, [this](const doa_t& m, const auto& info) {
    if (StampOk(kDoaGate, m.header.utime, info)) OnDoa(m);
  });
  node->Subscribe<people_detections_t>(options_.people_audio_channel,
                                       [this](const people_detections_t& m, const auto& info) {
                                         if (!StampOk(kHeardGate, m.header.utime, info)) return;
                                         const auto heard = HeardLinearDirections(m);
                                         Push(m.header.utime, [this, heard](common::Utime t) {
                                           for (const auto& d : heard) map_.OnHeardDirection(t, d);
                                         });
                                       });
  node->AddTimer(1.0, [this] { UpdateStatus(); });
}

// One far-future stamp must not become the queue's clock (every later input "late").
bool HandheldSoundMapNode::StampOk(Gate gate, common::Utime utime,
                                   const common::ReceiveInfo& info) {
  if (gates_.Accept(gate, utime, info.receive_time_s)) return true;
  node_->Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
  return false;
}

void HandheldSoundMapNode::PublishMap(common::Utime utime) {
  sound_map_t msg = LinearSoundMapMessage(map_, utime);
  map_pub_.Publish(&msg);
  last_publish_ = utime;
}

void HandheldSoundMapNode::Push(common::Utime utime, Apply apply) {
  newest_ = std::max(newest_, utime);
  if (!queue_.Push(utime, std::move(apply))) return;
  queue_.Release([this](common::Utime t, Apply& f) { ApplyInput(t, f); });
}

void HandheldSoundMapNode::ApplyInput(common::Utime utime, Apply& apply) {
  apply(utime);
  if (utime - last_publish_ >= common::SecondsToUtime(options_.publish_period_s)) PublishMap(utime);
}

void HandheldSoundMapNode::OnPose(const pose_t& m) {
  Eigen::Isometry3d odom_from_rig;
  if (!IsometryFromPose(m, &odom_from_rig)) {
    ++bad_poses_;
    if (pose_warning_.Allow(common::SteadySeconds())) {
      SARMAP_LOG(WARN) << options_.pose_channel
                       << ": non-finite position or non-unit quaternion, dropped (" << bad_poses_
                       << " so far)";
    }
    return;
  }
  const Eigen::Isometry3d odom_from_sensor = odom_from_rig * rig_from_sensor_;
  Push(m.header.utime,
       [this, odom_from_sensor](common::Utime t) { map_.OnPose(t, odom_from_sensor); });
}

void HandheldSoundMapNode::OnDoa(const doa_t& m) {
  auto doas = LinearDoasFromMessage(m, &other_kinds_);
  if (other_kinds_ > warned_kinds_) {
    warned_kinds_ = other_kinds_;
    if (kind_warning_.Allow(common::SteadySeconds())) {
      SARMAP_LOG(WARN) << other_kinds_
                       << " DOA(s) not KIND_ANGLE_1D ignored: this map needs a linear array's "
                          "cone angles (sarmap-sound-localisation with a linear array)";
    }
  }
  Push(m.header.utime, [this, doas](common::Utime t) { map_.OnDoa(t, doas); });
}

void HandheldSoundMapNode::UpdateStatus() {
  const auto& c = map_.counters();
  int converged = 0;
  const auto sources = map_.sources();
  for (const auto& s : sources) converged += s.converged;
  node_->SetStatusMessage(
      "sources " + std::to_string(sources.size()) + " (" + std::to_string(converged) +
      " converged, born " + std::to_string(c.sources_born) + ", merged " +
      std::to_string(c.sources_merged) + ", pruned " + std::to_string(c.sources_pruned) +
      "), keyframes " + std::to_string(c.keyframes) + ", doa used " + std::to_string(c.doas_used) +
      " of " + std::to_string(c.doas) + " (no pose " + std::to_string(c.doas_without_pose) +
      ", gated out " + std::to_string(c.doas_gated_out) + "), bad poses " +
      std::to_string(bad_poses_) + ", late inputs " + std::to_string(queue_.dropped_late()) +
      ", off-clock stamps " + std::to_string(gates_.dropped()) + " (re-anchors " +
      std::to_string(gates_.reanchors()) + ")");
}

void HandheldSoundMapNode::Finish() {
  queue_.Flush([this](common::Utime t, Apply& f) { ApplyInput(t, f); });
  map_.Finish();
  if (newest_ > 0) PublishMap(newest_);
}

}  // namespace sound_map
}  // namespace sarmap
