#pragma once
// What sarmap-people-map does with its inputs, without the transport: PEOPLE_VISUAL,
// PEOPLE_AUDIO, SOUND_MAP, SLAM_ANCHORS and POSE messages go through a time-ordered queue and
// are applied to the PeopleMap in capture-time order, each detection with the robot pose
// interpolated at its capture time (a detection newer than the latest pose waits for a later
// pose, at most pose_wait_s). Seen people hang from the SLAM node of the pose they were first
// seen from: the intake asks SLAM to keep those nodes (SLAM_ANCHOR_REQUEST) and moves the people
// with the node poses SLAM_ANCHORS reports. The node (PeopleMapNode, people_map_node.h) gates the
// stamps, saves the state and publishes; the in-process mission (components/mission) feeds the same
// class directly.

#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/options.h"
#include "common/pose_history.h"
#include "common/stamp_gate.h"
#include "common/time.h"
#include "common/transform.h"
#include "people_map/people_map.h"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"

namespace sarmap {
namespace people_map {

// The options of sarmap-people-map (config/people_map.yaml).
struct PeopleMapNodeOptions {
  std::string robot_config = "config/robot.yaml";
  std::string state_file = "";  // "" = no persistence
  double save_period_s = 1.0;
  double publish_period_s = 1.0;
  double reorder_delay_s = 0.5;  // inputs are held this long to be applied in time order
  double max_pose_gap_s = 0.5;
  // A detection newer than the latest pose waits for a pose at or after its time (to be placed
  // between two poses, not with the last one): SLAM publishes late while it optimises, and a
  // pose 0.3 s old in a 35 deg/s turn puts a person 3.5 m away 0.6 m off. If none comes within
  // this long (the newest input's time), or the node stops first, it is dropped and counted.
  double pose_wait_s = 2.0;
  std::string visual_channel = "PEOPLE_VISUAL";
  std::string audio_channel = "PEOPLE_AUDIO";
  std::string sound_map_channel = "SOUND_MAP";
  std::string pose_channel = "POSE";
  std::string anchors_channel = "SLAM_ANCHORS";
  std::string anchor_request_channel = "SLAM_ANCHOR_REQUEST";
  std::string client_id = "sarmap-people-map";
  double request_repeat_s = 5.0;
  int max_anchor_nodes = 32;
  std::string output_channel = "PEOPLE_MAP";
  // Per input channel: 20 s of 15 Hz PEOPLE_VISUAL or POSE, longer than the node's longest pause.
  int input_queue_capacity = 300;
  common::StampGateOptions stamp_gate;
  PeopleMapOptions map;
  template <class V>
  void Visit(V& v) {
    v("robot_config", robot_config, "robot extrinsics YAML (camera and array on the base)");
    v("state_file", state_file, "where the people map is saved and resumed from (\"\": nowhere)");
    v("save_period_s", save_period_s, "seconds between state saves (when changed)", Positive());
    v("publish_period_s", publish_period_s, "PEOPLE_MAP is also republished this often",
      Positive());
    v("reorder_delay_s", reorder_delay_s,
      "inputs wait this long to be applied in capture-time order", NonNegative());
    v("max_pose_gap_s", max_pose_gap_s,
      "largest gap to a known pose accepted for a detection (further: dropped and counted)",
      Positive());
    v("pose_wait_s", pose_wait_s,
      "a detection newer than the latest pose waits this long (message time) for a later pose to "
      "interpolate from, else it is dropped (never placed with an extrapolated pose)",
      NonNegative());
    v("visual_channel", visual_channel, "people seen");
    v("audio_channel", audio_channel, "people heard");
    v("sound_map_channel", sound_map_channel, "sound-source map");
    v("pose_channel", pose_channel, "robot pose in the map");
    v("anchors_channel", anchors_channel,
      "SLAM's node poses after each optimisation: seen people move with their node");
    v("anchor_request_channel", anchor_request_channel,
      "the SLAM nodes seen people hang from are asked for here");
    v("client_id", client_id, "client id in SLAM_ANCHOR_REQUEST");
    v("request_repeat_s", request_repeat_s,
      "re-send the anchor request this often (wall clock; 0: only on change)", NonNegative());
    v("max_anchor_nodes", max_anchor_nodes,
      "at most this many SLAM nodes are asked for, those of the people reported (confirmed "
      "people's first, then the people seen last; each costs SLAM_ANCHORS three covariance "
      "rows); people beyond stay where they are. At most sarmap-slam's "
      "max_anchor_ids_per_request",
      AtLeast(1));
    v("output_channel", output_channel, "the people map");
    v("input_queue_capacity", input_queue_capacity,
      "Messages held per input channel while the node is busy (a state save, a publication); "
      "beyond it the oldest are lost",
      AtLeast(1));
    v("stamp_gate", stamp_gate,
      "inputs stamped far from their stream's clock are dropped and counted, never adopted");
    v("map", map, "people map");
  }
};

// The people reported at `utime` as PEOPLE_MAP.
sarmap::people_map_t PeopleMapMessage(const std::vector<Person>& people, common::Utime utime);

class PeopleMapIntake {
 public:
  using Request = std::function<void(sarmap::slam_anchor_request_t&)>;
  // `map` must outlive the intake. `on_applied(utime)` is called once after each release of
  // inputs that changed the map (the node publishes PEOPLE_MAP there), with the newest applied
  // input's utime: a batch released together (a late pose places every detection that waited
  // for it) is one snapshot, not a burst a subscriber's queue has to hold. `request` whenever
  // the SLAM nodes the seen people hang from change.
  PeopleMapIntake(const PeopleMapNodeOptions& options, const common::Rigid3d& base_from_camera,
                  const common::Rigid3d& base_from_mic, PeopleMap* map,
                  std::function<void(common::Utime latest_utime)> on_applied = nullptr,
                  Request request = nullptr);

  void OnPose(const sarmap::pose_t& m);
  void OnSeen(const sarmap::people_detections_t& m);   // PEOPLE_VISUAL
  void OnHeard(const sarmap::people_detections_t& m);  // PEOPLE_AUDIO
  void OnSoundMap(const sarmap::sound_map_t& m);
  // False (dropped) when a node pose is not finite.
  bool OnAnchors(const sarmap::slam_anchors_t& m);
  // The anchor request for the map's current anchor nodes, stamped `utime`.
  void SendRequest(common::Utime utime);
  // Applies what is due (the node's timer calls it between inputs).
  void Release();
  // No more inputs: everything queued is applied (without on_applied), detections still waiting
  // for a pose are placed if one came, else dropped (with on_applied).
  void Finish();

  // The newest input time that changed the map (0: none yet; a resumed map's last detection
  // until then).
  common::Utime latest_utime() const { return latest_utime_; }
  void set_latest_utime(common::Utime utime) { latest_utime_ = utime; }
  // Set when an input changed the map; the node clears it after saving.
  bool dirty() const { return dirty_; }
  void clear_dirty() { dirty_ = false; }
  int64_t without_pose() const { return without_pose_; }
  int64_t dropped_late() const { return queue_.dropped_late(); }
  // POSEs whose node ids began again (SLAM restarted without its state): anchors forgotten.
  int64_t slam_restarts() const { return slam_restarts_; }

 private:
  void Applied(common::Utime utime);
  // on_applied once if anything was applied since the last call.
  void NoticeApplied();
  std::optional<common::StampedPose> PoseAt(common::Utime utime);
  void PlaceWaiting(bool final);
  void WhenPosed(common::Utime utime, std::function<void()> place);
  // The SLAM node of the pose at `utime` and that node's latest known map pose (node -1 when
  // unknown).
  PoseNode NodeAt(common::Utime utime) const;
  void RequestIfAnchorsChanged();

  PeopleMapNodeOptions options_;
  common::Rigid3d base_from_camera_, base_from_mic_;
  PeopleMap* map_;
  std::function<void(common::Utime)> on_applied_;
  bool applied_since_notice_ = false;
  Request request_;
  common::PoseHistory poses_;
  // The node id of each POSE where it changed (the last pose_history window), and the latest
  // known map pose of the nodes in it and of the anchors: a node's first pose (the scan that
  // made it) until SLAM_ANCHORS reports it.
  std::deque<std::pair<common::Utime, int64_t>> pose_nodes_;
  std::map<int64_t, common::Rigid2d> node_poses_;
  std::vector<int64_t> requested_anchors_;
  // The newest POSE's time and node id: a newer POSE with a smaller node id is a new SLAM graph.
  common::Utime newest_pose_utime_ = INT64_MIN;
  int64_t newest_node_id_ = -1;
  int64_t slam_restarts_ = 0;
  int64_t graph_epoch_ = 0;  // counts SLAM restarts; node ids are only compared within one
  common::TimeOrderedQueue<std::function<void()>> queue_;
  // Detections released from the queue before a pose at or after their time arrived, oldest
  // first: placed as soon as POSE catches up, or after pose_wait_s.
  std::deque<std::pair<common::Utime, std::function<void()>>> waiting_for_pose_;
  common::Utime newest_input_utime_ = INT64_MIN;
  common::Utime latest_utime_ = 0;
  bool dirty_ = false;
  int64_t without_pose_ = 0;
};

}  // namespace people_map
}  // namespace sarmap
