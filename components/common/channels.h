#pragma once
// The stack's default channels and the message type each carries (ARCHITECTURE.md).
// Nodes take channel names from their options; this table is the default and what the
// monitor and log tools use to decode.

#include <string>
#include <vector>

namespace sarmap {
namespace common {

struct ChannelSpec {
  const char* channel;
  const char* type;  // LCM type name in package sarmap
};

inline const std::vector<ChannelSpec>& DefaultChannels() {
  static const std::vector<ChannelSpec> channels = {
      {"ODOM", "odometry_t"},
      {"DEPTH", "image_t"},
      {"RGB", "image_t"},
      {"SCAN", "laser_scan_t"},
      {"AUDIO", "audio_frame_t"},
      {"DOA", "doa_t"},
      {"DOA_MAP", "doa_t"},  // onset-weighted directions for the sound map
      {"SPEECH", "speech_event_t"},
      {"PEOPLE_VISUAL", "people_detections_t"},
      {"PEOPLE_AUDIO", "people_detections_t"},
      {"POSE", "pose_t"},
      {"RIG_POSE", "pose_t"},  // a hand-held rig's RGB-D odometry (sarmap-rgbd-odometry)
      {"MAP", "occupancy_grid_t"},
      {"SLAM_ANCHORS", "slam_anchors_t"},
      {"SLAM_ANCHOR_REQUEST", "slam_anchor_request_t"},
      {"SOUND_MAP", "sound_map_t"},
      {"PEOPLE_MAP", "people_map_t"},
      {"CMD_VEL", "velocity_command_t"},
      {"TELEOP", "teleop_t"},
      {"EXPLORE_STATUS", "explore_status_t"},
      {"SIM_TRUTH", "sim_truth_t"},
      {"SIM_FLOOR", "occupancy_grid_t"},  // the simulator's reachable floor (world frame)
      {"PM_ORDERS", "pm_orders_t"},
      {"PM_INFO", "pm_info_t"},
      {"PM_OUTPUT", "pm_output_t"},
  };
  return channels;
}

}  // namespace common
}  // namespace sarmap
