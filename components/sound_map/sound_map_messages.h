#pragma once
// What sarmap-sound-map and sarmap-log-sound-map share: the node's options and the
// conversions between LCM messages and the core's OnlineSoundMap (header-only: the core
// library has no LCM).
#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "common/compression.h"
#include "common/message_conversions.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "sound_map/online_sound_map.h"

namespace sarmap {
namespace sound_map {

struct SoundMapNodeOptions {
  std::string client_id = "sarmap-sound-map";
  std::string robot_config = "config/robot.yaml";
  std::string doa_channel = "DOA";
  std::string people_audio_channel = "PEOPLE_AUDIO";
  std::string pose_channel = "POSE";
  std::string anchors_channel = "SLAM_ANCHORS";
  std::string anchor_request_channel = "SLAM_ANCHOR_REQUEST";
  std::string sound_map_channel = "SOUND_MAP";
  std::string site_map_channel = "MAP";  // the mapped site: a person must lie on it
  // Per input channel: 20 s of 15 Hz POSE, longer than the node's longest solve or save.
  int input_queue_capacity = 300;
  // Inputs wait this long for older ones still on their way. PEOPLE_AUDIO comes 1.9-2.8 s after
  // its time (the utterance is decoded when it ends and its keyword hits wait 2 s for the other
  // beams'), and POSE up to 2.8 s late while SLAM optimises a long mission's graph: with 0.3 s
  // every heard direction was dropped as late and no source was ever marked a person.
  double reorder_delay_s = 3.0;
  double publish_period_s = 0.5;
  double request_repeat_s = 5.0;
  std::string state_file = "";  // "" = no persistence
  double state_save_period_s = 5.0;
  bool resume = false;
  common::StampGateOptions
      stamp_gate;  // the node's inputs (the log replay reads a log's own clock)
  OnlineSoundMapOptions map;
  template <class V>
  void Visit(V& v) {
    v("client_id", client_id, "client id in SLAM_ANCHOR_REQUEST");
    v("robot_config", robot_config, "robot description with base_from_mic_array");
    v("doa_channel", doa_channel, "directions of arrival in");
    v("people_audio_channel", people_audio_channel, "heard people in (marks sources as persons)");
    v("pose_channel", pose_channel, "current map_from_base pose in");
    v("anchors_channel", anchors_channel, "SLAM anchors and joint covariance in");
    v("anchor_request_channel", anchor_request_channel, "anchor node requests out");
    v("sound_map_channel", sound_map_channel, "the sound map out");
    v("site_map_channel", site_map_channel,
      "occupancy grid of the mapped site in (a person must lie near its known cells; '' = none)");
    v("input_queue_capacity", input_queue_capacity,
      "Messages held per input channel while the node is busy (a state save, a solve); beyond "
      "it the oldest are lost",
      AtLeast(1));
    v("reorder_delay_s", reorder_delay_s,
      "inputs are processed in time order once this much newer data arrived", NonNegative());
    v("publish_period_s", publish_period_s, "SOUND_MAP period, message time", Positive());
    v("request_repeat_s", request_repeat_s,
      "re-send the anchor request this often (wall clock; 0: only on change)", NonNegative());
    v("state_file", state_file,
      "where the map's state is saved (written beside it, then renamed over it: crash-safe) and "
      "resumed from (\"\": nowhere)");
    v("state_save_period_s", state_save_period_s,
      "save the state this often when it changed (wall clock)", Positive());
    v("resume", resume,
      "start from state_file if it exists (after a crash or kill, the launcher restarts us)");
    v("stamp_gate", stamp_gate,
      "inputs stamped far from their stream's clock are dropped and counted, never adopted");
    v("map", map, "sound map estimator");
  }
  void Validate(common::Validator& check) const {
    check.That(!robot_config.empty(), "robot_config", "must name the robot description");
  }
};

inline ArrayMount MountFromRobot(const common::RobotOptions& robot) {
  ArrayMount mount;
  mount.x_m = robot.base_from_mic_array.x_m;
  mount.y_m = robot.base_from_mic_array.y_m;
  mount.z_m = robot.base_from_mic_array.z_m;
  mount.yaw_rad = robot.base_from_mic_array.yaw_rad;
  return mount;
}

// The planar pose (x, y, yaw of the x axis) of a 6-DoF pose_t.
inline common::Rigid2d PlanarPose(const sarmap::pose_t& msg) {
  return common::ToRigid3d(msg.position_m, msg.orientation).ToRigid2d();
}

// DOAs with finite values (any kind; the map counts the kinds it cannot use).
inline std::vector<OnlineSoundMap::Doa> DoasFromMessage(const sarmap::doa_t& msg) {
  std::vector<OnlineSoundMap::Doa> doas;
  for (const auto& s : msg.sources) {
    OnlineSoundMap::Doa d;
    d.track_id = s.track_id;
    d.kind = s.kind;
    d.azimuth_rad = s.azimuth_rad;
    d.elevation_rad = s.elevation_rad;
    d.covariance << s.covariance[0], s.covariance[1], s.covariance[2], s.covariance[3];
    d.sound_class = s.sound_class >= 0 && s.sound_class <= 4 ? s.sound_class : 0;
    if (!std::isfinite(d.azimuth_rad) || !std::isfinite(d.elevation_rad) || !d.covariance.allFinite()) continue;
    doas.push_back(d);
  }
  return doas;
}

// False when the covariance does not match the anchors (3(1+n) square).
inline bool AnchorsFromMessage(const sarmap::slam_anchors_t& msg, common::Rigid2d* current,
                               std::vector<std::pair<int64_t, common::Rigid2d>>* anchors,
                               Eigen::MatrixXd* cov) {
  const int n = msg.num_anchors;
  const int dim = msg.covariance_dim;
  if (dim != 3 * (1 + n) || static_cast<int>(msg.covariance.size()) != dim ||
      static_cast<int>(msg.anchors.size()) != n)
    return false;
  cov->resize(dim, dim);
  for (int r = 0; r < dim; ++r) {
    if (static_cast<int>(msg.covariance[r].size()) != dim) return false;
    for (int c = 0; c < dim; ++c) (*cov)(r, c) = msg.covariance[r][c];
  }
  *current = common::Rigid2d(msg.current.x_m, msg.current.y_m, msg.current.yaw_rad);
  anchors->clear();
  for (const auto& a : msg.anchors)
    anchors->emplace_back(a.node_id, common::Rigid2d(a.x_m, a.y_m, a.yaw_rad));
  return true;
}

// DOA track ids of heard people.
inline std::vector<int64_t> HeardTracks(const sarmap::people_detections_t& msg) {
  std::vector<int64_t> tracks;
  for (const auto& d : msg.detections)
    if (d.cue == sarmap::person_detection_t::CUE_HEARD && d.track_id >= 0) tracks.push_back(d.track_id);
  return tracks;
}

// Heard people of PEOPLE_AUDIO as azimuth observations in the array frame (by direction, not
// by track id: their track ids belong to the DOA stream sarmap-speech beams at).
inline std::vector<OnlineSoundMap::Doa> HeardDirections(const sarmap::people_detections_t& msg) {
  std::vector<OnlineSoundMap::Doa> out;
  for (const auto& d : msg.detections) {
    if (d.cue != sarmap::person_detection_t::CUE_HEARD) continue;
    OnlineSoundMap::Doa doa;
    doa.track_id = d.track_id;
    doa.kind = OnlineSoundMap::kAzimuth;
    doa.azimuth_rad = d.azimuth_rad;
    doa.elevation_rad = d.elevation_rad;
    doa.covariance << d.direction_covariance[0], d.direction_covariance[1], d.direction_covariance[2],
        d.direction_covariance[3];
    doa.called = !d.keyword.empty();
    if (!std::isfinite(doa.azimuth_rad) || !doa.covariance.allFinite()) continue;
    out.push_back(doa);
  }
  return out;
}

// The box (map frame) of a grid's known cells; false when it has none or cannot be read.
inline bool SiteBox(const sarmap::occupancy_grid_t& grid, Eigen::Vector2d* min_m,
                    Eigen::Vector2d* max_m) {
  if (grid.width <= 0 || grid.height <= 0 || !(grid.resolution_m > 0)) return false;
  const size_t cells = static_cast<size_t>(grid.width) * grid.height;
  std::vector<uint8_t> data;
  if (grid.compression == sarmap::occupancy_grid_t::COMPRESSION_ZSTD) {
    std::string error;
    if (!common::DecompressBytes(grid.data.data(), grid.data.size(), cells, &data, &error))
      return false;
  } else {
    if (grid.data.size() != cells) return false;
    data.assign(grid.data.begin(), grid.data.end());
  }
  int c0 = grid.width, c1 = -1, r0 = grid.height, r1 = -1;
  for (int r = 0; r < grid.height; ++r)
    for (int c = 0; c < grid.width; ++c)
      if (static_cast<int8_t>(data[static_cast<size_t>(r) * grid.width + c]) >= 0) {
        c0 = std::min(c0, c), c1 = std::max(c1, c), r0 = std::min(r0, r), r1 = std::max(r1, r);
      }
  if (c1 < 0) return false;
  const double ca = std::cos(grid.origin_yaw_rad), sa = std::sin(grid.origin_yaw_rad);
  *min_m = Eigen::Vector2d::Constant(INFINITY);
  *max_m = Eigen::Vector2d::Constant(-INFINITY);
  for (double u : {static_cast<double>(c0), c1 + 1.0})
    for (double v : {static_cast<double>(r0), r1 + 1.0}) {
      const Eigen::Vector2d p(grid.origin_x_m + grid.resolution_m * (ca * u - sa * v),
                              grid.origin_y_m + grid.resolution_m * (sa * u + ca * v));
      *min_m = min_m->cwiseMin(p);
      *max_m = max_m->cwiseMax(p);
    }
  return true;
}

inline sarmap::sound_map_t SoundMapMessage(const OnlineSoundMap& map, int64_t utime) {
  sarmap::sound_map_t msg{};
  msg.header.utime = utime;
  msg.header.frame = "map";
  for (const auto& s : map.Sources(utime)) {
    sarmap::sound_source_t out{};
    out.id = s.id;
    for (int i = 0; i < 3; ++i) out.position_m[i] = s.position_m[i];
    common::FromCovariance3(s.covariance, out.covariance);
    out.state = static_cast<int8_t>(s.state);
    out.hypotheses_left = s.hypotheses_left;
    out.is_person = s.is_person;
    out.first_heard_utime = s.first_heard_utime;
    out.last_heard_utime = s.last_heard_utime;
    out.num_observations = s.num_observations;
    out.has_position = s.has_position;
    out.bearing_rad = s.bearing_rad;
    out.bearing_variance = s.bearing_variance;
    for (int i = 0; i < 3; ++i) out.bearing_origin_m[i] = s.bearing_origin_m[i];
    out.sound_class = static_cast<int8_t>(s.sound_class);
    out.class_confidence = static_cast<float>(s.class_confidence);
    out.priority = static_cast<int8_t>(s.priority);
    msg.sources.push_back(out);
  }
  msg.num_sources = static_cast<int32_t>(msg.sources.size());
  return msg;
}

}  // namespace sound_map
}  // namespace sarmap
