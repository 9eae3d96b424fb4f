#pragma once
// ROS 1 bags <-> sarmap LCM logs (sarmap-log import-rosbag / export-rosbag), through Debian's
// rosbag_storage and ROS message headers: no ROS installation needed.
//
// Import (each ROS type to its sarmap type, the channel from `topics` or the type's default):
//   sensor_msgs/LaserScan            -> laser_scan_t    SCAN   (each scan's own geometry)
//   nav_msgs/Odometry                -> odometry_t      ODOM
//   tf2_msgs/TFMessage on /tf        -> odometry_t      ODOM   (odom_frame -> base_frame only)
//   tf2_msgs/TFMessage on /tf_static -> the extrinsics file (config/robot.yaml's form)
//   sensor_msgs/Image 16UC1 (mm), 32FC1 (m) -> image_t DEPTH (mm, lossless compression)
//   sensor_msgs/Image rgb8 bgr8 mono8       -> image_t RGB  (raw)
//   sensor_msgs/CompressedImage JPEG, PNG   -> image_t RGB  (as it came; size from its header)
//     with the intrinsics of the sensor_msgs/CameraInfo in the camera's namespace (the image
//     topic's; one level up for image_transport's .../compressed)
//   audio_common_msgs/AudioData(Stamped)    -> audio_frame_t AUDIO (raw S16LE PCM, format
//     from audio_common_msgs/AudioInfo or the options)
//   geometry_msgs/PoseStamped        -> pose_t          POSE
//   nav_msgs/OccupancyGrid           -> occupancy_grid_t MAP
//   visualization_msgs/MarkerArray   -> people_map_t    PEOPLE_MAP (as export writes it)
// Export writes POSE, MAP and PEOPLE_MAP as the same ROS types (MarkerArray: one SPHERE per
// person, namespace "people", 1-sigma diameters, the person's cues and confidence in `text`).

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/options.h"

namespace sarmap {
namespace logtools {

struct RosbagOptions {
  // "TOPIC=CHANNEL": where a topic goes (import) or comes from (export: "TOPIC=POSE" etc.).
  // Topics of a supported type not listed go to their type's default channel.
  std::vector<std::string> topics;
  // "ROS_FRAME=SARMAP_FRAME": frame names renamed on import (and back on export).
  std::vector<std::string> frames{"base_link=base", "base_footprint=base"};
  // /tf odometry: the transform odom_frame -> base_frame (ROS names) becomes odometry_t.
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::string tf_odom_channel = "ODOM";
  // /tf_static: these frames' poses in base_frame are written to the extrinsics file.
  std::string camera_frame = "camera_depth_optical_frame";
  std::string mic_array_frame = "mic_array";
  std::string laser_frame = "";  // "" = the first LaserScan's frame_id
  // Raw audio without an AudioInfo topic.
  int audio_sample_rate_hz = 16000;
  int audio_channels = 1;
  std::string audio_device = "rosbag";
  // Export.
  std::string pose_channel = "POSE";
  std::string map_channel = "MAP";
  std::string people_channel = "PEOPLE_MAP";
  std::string pose_topic = "/sarmap/pose";
  std::string map_topic = "/map";
  std::string people_topic = "/sarmap/people";

  template <class V>
  void Visit(V& v) {
    v("topics", topics,
      "TOPIC=CHANNEL pairs; unlisted topics of a supported type use the type's default channel");
    v("frames", frames, "ROS_FRAME=SARMAP_FRAME renames");
    v("odom_frame", odom_frame, "/tf odometry: parent frame (ROS name)");
    v("base_frame", base_frame,
      "/tf odometry: child frame, and the frame extrinsics are given in (ROS name)");
    v("tf_odom_channel", tf_odom_channel, "channel for /tf odometry");
    v("camera_frame", camera_frame, "/tf_static frame written as base_from_camera");
    v("mic_array_frame", mic_array_frame, "/tf_static frame written as base_from_mic_array");
    v("laser_frame", laser_frame,
      "/tf_static frame written as the SLAM laser pose (\"\": the scans' frame)");
    v("audio_sample_rate_hz", audio_sample_rate_hz, "raw audio without AudioInfo: sample rate");
    v("audio_channels", audio_channels, "raw audio without AudioInfo: channels (interleaved S16LE)",
      InRange(1, 64));
    v("audio_device", audio_device, "audio_frame_t device_id");
    v("pose_channel", pose_channel, "export: pose_t channel");
    v("map_channel", map_channel, "export: occupancy_grid_t channel");
    v("people_channel", people_channel, "export: people_map_t channel");
    v("pose_topic", pose_topic, "export: geometry_msgs/PoseStamped topic");
    v("map_topic", map_topic, "export: nav_msgs/OccupancyGrid topic");
    v("people_topic", people_topic, "export: visualization_msgs/MarkerArray topic");
  }
  void Validate(common::Validator& check) const;
};

struct TopicSummary {
  std::string topic, type, channel;  // channel "" when not imported
  int64_t messages = 0;              // in the bag
  int64_t written = 0;               // events written
  int64_t undecodable = 0;           // messages that did not deserialise (skipped)
  std::string note;                  // why not imported, or what was converted
};

struct RosbagImportResult {
  std::vector<TopicSummary> topics;
  std::map<std::string, int64_t> channel_counts;
  std::string extrinsics_path;  // "" when the bag has no /tf_static
  std::vector<std::string> warnings;
};

// The bag's topics, types and message counts (also what an error lists).
std::vector<TopicSummary> ListBag(const std::string& bag_path);
std::string FormatTopics(const std::vector<TopicSummary>& topics);

// Converts `bag_path` into the LCM log `log_path`. Event times are the bag's record times,
// header.utime the messages' stamps. With /tf_static, writes `extrinsics_path` (unless ""). A
// topic listed in options.topics whose type is not supported, or a bag with nothing to
// import, throws std::runtime_error naming every topic and type the bag holds; other topics
// of unsupported types are skipped and listed. `progress` gets the fraction done.
RosbagImportResult ImportRosbag(const std::string& bag_path, const std::string& log_path,
                                const RosbagOptions& options, const std::string& extrinsics_path,
                                const std::function<void(double)>& progress = nullptr);

struct RosbagExportResult {
  std::map<std::string, int64_t> topic_counts;
};
// Writes POSE, MAP (zstd or not) and PEOPLE_MAP of an LCM log as ROS messages.
RosbagExportResult ExportRosbag(const std::string& log_path, const std::string& bag_path,
                                const RosbagOptions& options,
                                const std::function<void(double)>& progress = nullptr);

}  // namespace logtools
}  // namespace sarmap
