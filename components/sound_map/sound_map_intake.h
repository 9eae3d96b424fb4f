#pragma once
// What sarmap-sound-map does with its inputs, without the transport: POSE, SLAM_ANCHORS, DOA
// and PEOPLE_AUDIO go through a time-ordered queue into the OnlineSoundMap, MAP bounds the site;
// after each input the anchor request is sent when the map's anchors changed, and SOUND_MAP
// every publish_period_s of message time. The node (sound_map_node.cc) gates the stamps, saves
// the state and publishes; the in-process mission (components/mission) feeds the same class.

#include <functional>
#include <string>

#include "common/time.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "sound_map/online_sound_map.h"
#include "sound_map/sound_map_messages.h"

namespace sarmap {
namespace sound_map {

class SoundMapIntake {
 public:
  using Publish = std::function<void(sarmap::sound_map_t&)>;  // may stamp the header
  using Request = std::function<void(sarmap::slam_anchor_request_t&)>;
  // `map` must outlive the intake.
  SoundMapIntake(const SoundMapNodeOptions& options, OnlineSoundMap* map, Publish publish,
                 Request request);

  void OnPose(const sarmap::pose_t& m);
  // False (nothing queued) when the covariance does not match the anchors.
  bool OnAnchors(const sarmap::slam_anchors_t& m);
  void OnDoa(const sarmap::doa_t& m);
  void OnHeard(const sarmap::people_detections_t& m);  // PEOPLE_AUDIO
  // The mapped site only grows: applied at once, not in time order.
  void OnSiteMap(const sarmap::occupancy_grid_t& m);
  // The anchor request for the map's current anchors, stamped `utime`.
  void SendRequest(common::Utime utime);
  // No more inputs: everything queued is applied and the final map published.
  void Finish();

  common::Utime newest_utime() const { return newest_; }
  bool changed() const { return changed_; }
  void clear_changed() { changed_ = false; }
  int64_t dropped_late() const { return queue_.dropped_late(); }

 private:
  void Push(common::Utime utime, std::function<void(common::Utime)> fn);
  void AfterInput(common::Utime utime);
  void PublishMap(common::Utime utime);

  SoundMapNodeOptions options_;
  OnlineSoundMap* map_;
  Publish publish_;
  Request request_;
  common::TimeOrderedQueue<std::function<void(common::Utime)>> queue_;
  common::Utime last_publish_ = INT64_MIN / 2, newest_ = 0;
  int64_t warned_kind_ = 0;
  bool changed_ = false;
};

}  // namespace sound_map
}  // namespace sarmap
