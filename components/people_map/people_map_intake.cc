#include "people_map/people_map_intake.h"

#include <algorithm>
#include <cmath>

#include "common/logging.h"
#include "common/message_conversions.h"
#include "sarmap/doa_source_t.hpp"

namespace sarmap {
namespace people_map {

using common::Utime;

namespace {
// Each input is ordered within its own stream: a keyword is published only after its
// utterance has been decoded (0.1-2 s after it was said), later than the visual detections
// of the same instant, and must not be dropped as late.
constexpr int kSeenStream = 0, kHeardStream = 1, kSoundMapStream = 2, kAnchorsStream = 3;
// How long node ids of past poses are kept (as the pose history).
constexpr double kPoseNodeWindowS = 60.0;
}  // namespace

sarmap::people_map_t PeopleMapMessage(const std::vector<Person>& people, Utime utime) {
  sarmap::people_map_t msg{};
  msg.header.utime = utime;
  msg.header.frame = "map";
  for (const auto& p : people) {
    sarmap::mapped_person_t m{};
    m.id = p.id;
    for (int i = 0; i < 3; ++i) m.position_m[i] = p.position_m[i];
    common::FromCovariance3(p.covariance, m.covariance);
    m.confidence = static_cast<float>(p.confidence);
    m.cues = static_cast<int8_t>(p.cues);
    m.num_detections = p.num_detections;
    m.people_count = p.people_count;
    m.first_detected_utime = p.first_detected_utime;
    m.last_detected_utime = p.last_detected_utime;
    m.keyword = p.keyword;
    m.sound_source_id = p.sound_source_id;
    msg.people.push_back(m);
  }
  msg.num_people = static_cast<int32_t>(msg.people.size());
  return msg;
}

PeopleMapIntake::PeopleMapIntake(const PeopleMapNodeOptions& options,
                                 const common::Rigid3d& base_from_camera,
                                 const common::Rigid3d& base_from_mic, PeopleMap* map,
                                 std::function<void(Utime)> on_applied, Request request)
    : options_(options),
      base_from_camera_(base_from_camera),
      base_from_mic_(base_from_mic),
      map_(map),
      on_applied_(std::move(on_applied)),
      request_(std::move(request)),
      poses_(common::SecondsToUtime(kPoseNodeWindowS),
             common::SecondsToUtime(options.max_pose_gap_s)),
      queue_(common::SecondsToUtime(options.reorder_delay_s)) {}

void PeopleMapIntake::Applied(Utime utime) {
  latest_utime_ = std::max(latest_utime_, utime);
  dirty_ = true;
  RequestIfAnchorsChanged();
  applied_since_notice_ = true;
}

void PeopleMapIntake::NoticeApplied() {
  if (!applied_since_notice_) return;
  applied_since_notice_ = false;
  if (on_applied_) on_applied_(latest_utime_);
}

void PeopleMapIntake::SendRequest(Utime utime) {
  sarmap::slam_anchor_request_t req{};
  req.header.utime = utime;
  req.header.frame = "map";
  req.client_id = options_.client_id;
  req.node_ids = map_->AnchorNodeIds(static_cast<size_t>(options_.max_anchor_nodes), utime);
  req.num_node_ids = static_cast<int32_t>(req.node_ids.size());
  requested_anchors_ = req.node_ids;
  if (request_) request_(req);
}

void PeopleMapIntake::RequestIfAnchorsChanged() {
  if (map_->AnchorNodeIds(static_cast<size_t>(options_.max_anchor_nodes), latest_utime_) !=
      requested_anchors_)
    SendRequest(latest_utime_);
}

PoseNode PeopleMapIntake::NodeAt(Utime utime) const {
  // The last node change at or before `utime`.
  auto it =
      std::upper_bound(pose_nodes_.begin(), pose_nodes_.end(), utime,
                       [](Utime t, const std::pair<Utime, int64_t>& e) { return t < e.first; });
  PoseNode node;
  if (it == pose_nodes_.begin()) return node;
  const int64_t id = std::prev(it)->second;
  const auto pose = node_poses_.find(id);
  if (id < 0 || pose == node_poses_.end()) return node;
  node.node_id = id;
  node.map_from_node = pose->second;
  return node;
}

std::optional<common::StampedPose> PeopleMapIntake::PoseAt(Utime utime) {
  auto pose = poses_.At(utime);
  if (!pose) {
    ++without_pose_;
    SARMAP_LOG(WARN) << "no robot pose within " << options_.max_pose_gap_s
                     << " s of a detection at " << utime << "; dropped (" << without_pose_
                     << " so far)";
  }
  return pose;
}

void PeopleMapIntake::PlaceWaiting(bool final) {
  const Utime pose_wait_us = common::SecondsToUtime(options_.pose_wait_s);
  while (!waiting_for_pose_.empty()) {
    const Utime utime = waiting_for_pose_.front().first;
    if (utime > poses_.newest_utime()) {
      if (!final && newest_input_utime_ - utime <= pose_wait_us) break;
      // Never placed with a pose extrapolated into a turn: dropped and counted.
      ++without_pose_;
      waiting_for_pose_.pop_front();
      continue;
    }
    waiting_for_pose_.front().second();
    waiting_for_pose_.pop_front();
    Applied(utime);
  }
}

// Runs `place` (which looks up the pose at `utime`) now if a pose at or after `utime` is known
// and nothing older waits, else queues it.
void PeopleMapIntake::WhenPosed(Utime utime, std::function<void()> place) {
  if (waiting_for_pose_.empty() && poses_.newest_utime() >= utime) {
    place();
    return;
  }
  waiting_for_pose_.emplace_back(utime, std::move(place));
}

void PeopleMapIntake::Release() {
  queue_.Release([&](Utime utime, std::function<void()>& apply) {
    apply();
    Applied(utime);
  });
  PlaceWaiting(false);
  NoticeApplied();
}

void PeopleMapIntake::Finish() {
  queue_.Flush([&](Utime utime, std::function<void()>& apply) {
    apply();
    latest_utime_ = std::max(latest_utime_, utime);
    dirty_ = true;
  });
  PlaceWaiting(true);
  NoticeApplied();
}

void PeopleMapIntake::OnPose(const sarmap::pose_t& m) {
  common::StampedPose p;
  p.utime = m.header.utime;
  p.pose = common::ToRigid3d(m.position_m, m.orientation);
  p.covariance = common::ToCovariance6(m.covariance);
  poses_.Add(p);
  if (m.node_id >= 0 && p.utime > newest_pose_utime_ && m.node_id < newest_node_id_) {
    // A SLAM restarted without its state numbers its nodes from 0 again: the ids the people
    // hang from now name other nodes. People stay where they are, anchored afresh when seen.
    ++slam_restarts_;
    SARMAP_LOG(WARN) << "POSE node id went back from " << newest_node_id_ << " to " << m.node_id
                     << " (SLAM restarted with a new graph): people no longer move with SLAM "
                        "nodes seen before";
    // The node bookkeeping starts again now (the new graph's nodes come from here on); the map
    // forgets its anchors in time order, after the detections and SLAM_ANCHORS of the old graph.
    pose_nodes_.clear();
    node_poses_.clear();
    ++graph_epoch_;
    queue_.Push(
        p.utime, [this] { map_->ForgetAnchors(); }, kAnchorsStream);
    newest_node_id_ = m.node_id;
  }
  if (p.utime > newest_pose_utime_) {
    newest_pose_utime_ = p.utime;
    if (m.node_id >= 0) newest_node_id_ = std::max(newest_node_id_, m.node_id);
  }
  if (m.node_id >= 0 && (pose_nodes_.empty() || pose_nodes_.back().second != m.node_id) &&
      (pose_nodes_.empty() || p.utime > pose_nodes_.back().first)) {
    pose_nodes_.emplace_back(p.utime, m.node_id);
    // A node's own scan gives its pose until SLAM reports it.
    node_poses_.emplace(m.node_id, p.pose.ToRigid2d());
    const Utime keep_after = p.utime - common::SecondsToUtime(kPoseNodeWindowS);
    while (pose_nodes_.size() > 1 && pose_nodes_[1].first <= keep_after) pose_nodes_.pop_front();
    // Node poses still needed: the recent poses' nodes and the people's anchors.
    if (node_poses_.size() > 2 * pose_nodes_.size() + 64) {
      const std::vector<int64_t> anchors = map_->AnchorNodeIds();
      for (auto it = node_poses_.begin(); it != node_poses_.end();) {
        const int64_t id = it->first;
        const bool recent = std::any_of(pose_nodes_.begin(), pose_nodes_.end(),
                                        [id](const auto& e) { return e.second == id; });
        if (recent || std::binary_search(anchors.begin(), anchors.end(), id)) {
          ++it;
        } else {
          it = node_poses_.erase(it);
        }
      }
    }
  }
  newest_input_utime_ = std::max(newest_input_utime_, p.utime);
  // POSE is the one input that never stops (detections do when nobody is in view; the sound
  // map publishes 3 s late): it moves the queue's clock.
  queue_.AdvanceTo(p.utime);
  Release();
}

void PeopleMapIntake::OnSeen(const sarmap::people_detections_t& m) {
  const Utime utime = m.header.utime;
  std::vector<SeenDetection> seen;
  for (const auto& d : m.detections) {
    if (!d.has_range || d.cue == sarmap::person_detection_t::CUE_HEARD) continue;
    SeenDetection s;
    s.position_camera_m = Eigen::Vector3d(d.position_m[0], d.position_m[1], d.position_m[2]);
    s.covariance_camera = common::ToCovariance3(d.position_covariance);
    s.confidence = d.confidence;
    s.cue = d.cue == sarmap::person_detection_t::CUE_SEEN_DEPTH ? kSeenDepth : kSeenRgbd;
    s.track_id = d.track_id;
    seen.push_back(s);
  }
  if (seen.empty()) return;
  newest_input_utime_ = std::max(newest_input_utime_, utime);
  queue_.Push(
      utime,
      [this, utime, seen] {
        WhenPosed(utime, [this, utime, seen] {
          if (auto pose = PoseAt(utime)) {
            const Eigen::Matrix3d planar = common::PlanarCovariance(pose->covariance);
            map_->AddSeen(utime, seen, pose->pose * base_from_camera_, planar,
                          pose->pose.translation().head<2>(), NodeAt(utime));
          }
        });
      },
      kSeenStream);
  Release();
}

void PeopleMapIntake::OnHeard(const sarmap::people_detections_t& m) {
  const Utime utime = m.header.utime;
  std::vector<HeardDetection> heard;
  for (const auto& d : m.detections) {
    HeardDetection h;
    h.azimuth_rad = d.azimuth_rad;
    h.elevation_rad = d.elevation_rad;
    h.azimuth_sigma_rad = std::sqrt(std::max(0.0, d.direction_covariance[0]));
    h.confidence = d.confidence;
    h.keyword = d.keyword;
    heard.push_back(h);
  }
  if (heard.empty()) return;
  newest_input_utime_ = std::max(newest_input_utime_, utime);
  queue_.Push(
      utime,
      [this, utime, heard] {
        WhenPosed(utime, [this, utime, heard] {
          if (auto pose = PoseAt(utime)) map_->AddHeard(utime, heard, pose->pose * base_from_mic_);
        });
      },
      kHeardStream);
  Release();
}

void PeopleMapIntake::OnSoundMap(const sarmap::sound_map_t& m) {
  std::vector<SoundSource> sources;
  for (const auto& s : m.sources) {
    // Only placed voices can be people: a bearing has no position yet, and a machine or an
    // alarm is never a person, whatever the keyword spotter heard near it.
    if (!s.has_position || s.sound_class != sarmap::doa_source_t::SOUND_CLASS_VOICE) continue;
    SoundSource src;
    src.id = s.id;
    src.position_m = Eigen::Vector3d(s.position_m[0], s.position_m[1], s.position_m[2]);
    src.covariance = common::ToCovariance3(s.covariance);
    src.is_person = s.is_person;
    src.converged = s.state == sarmap::sound_source_t::STATE_CONVERGED;
    sources.push_back(src);
  }
  const Utime utime = m.header.utime;
  queue_.Push(
      utime, [this, utime, sources] { map_->UpdateSoundSources(utime, sources); }, kSoundMapStream);
  Release();
}

bool PeopleMapIntake::OnAnchors(const sarmap::slam_anchors_t& m) {
  std::map<int64_t, common::Rigid2d> nodes;
  auto add = [&nodes](const sarmap::slam_anchor_t& a) {
    if (a.node_id < 0) return true;
    if (!std::isfinite(a.x_m) || !std::isfinite(a.y_m) || !std::isfinite(a.yaw_rad)) return false;
    nodes[a.node_id] = common::Rigid2d(a.x_m, a.y_m, a.yaw_rad);
    return true;
  };
  if (!add(m.current)) return false;
  for (const auto& a : m.anchors)
    if (!add(a)) return false;
  if (nodes.empty()) return true;
  const Utime utime = m.header.utime;
  const int64_t epoch = graph_epoch_;
  queue_.Push(
      utime,
      [this, nodes, epoch] {
        // The node poses of a graph SLAM has since restarted from would name the new graph's.
        if (epoch == graph_epoch_) {
          for (const auto& [id, pose] : nodes) {
            auto known = node_poses_.find(id);
            if (known != node_poses_.end()) known->second = pose;
          }
        }
        map_->MoveWithNodes(nodes);
      },
      kAnchorsStream);
  Release();
  return true;
}

}  // namespace people_map
}  // namespace sarmap
