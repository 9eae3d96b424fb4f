#pragma once
// What the operator's web page shows, kept up to date by the node and served as JSON. Free of
// LCM and of the HTTP server, so it can be tested and reused (the mission report draws the
// same things).

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "common/time.h"

namespace sarmap {
namespace viewer {

// A 3-sigma ellipse of a 2x2 covariance: semi-axes and the angle of the major axis.
struct Ellipse {
  double major_m = 0, minor_m = 0, angle_rad = 0;
};
Ellipse ThreeSigmaEllipse(const Eigen::Matrix2d& covariance);

struct GridImage {
  int width = 0, height = 0;
  double resolution_m = 0.05, origin_x_m = 0, origin_y_m = 0;
  std::vector<int8_t> cells;  // -1 unknown, 0..100
};

struct PersonView {
  int64_t id = 0;
  double x_m = 0, y_m = 0;
  Ellipse ellipse;
  double confidence = 0;
  bool seen = false, seen_depth_only = false, heard = false;
  int count = 1;
  std::string keyword;
};

struct SourceView {
  int64_t id = 0;
  double x_m = 0, y_m = 0;
  Ellipse ellipse;
  std::string state;
  bool is_person = false;
  std::string sound_class = "unknown";  // voice, alarm, machinery, music, unknown
  bool calling = false;                 // a voice that called for help
  // false: a bearing from (x_m, y_m), the point it was heard from; its range is not known.
  bool has_position = true;
  double bearing_rad = 0, bearing_sigma_rad = 0;
};

struct ProcessView {
  std::string deputy, command, state;
  int pid = 0, restarts = 0;
  double cpu_percent = 0, rss_mb = 0;
};

struct NodeView {
  std::string name, message;
  int64_t dropped = 0;
  double last_seen_s = 0;  // steady clock
};

// What sarmap-explore is doing (EXPLORE_STATUS).
struct MissionView {
  std::string state, driven_by, goal_kind;
  bool has_goal = false;
  double goal_x_m = 0, goal_y_m = 0;
  std::vector<Eigen::Vector2d> path;
  int frontiers = 0, recoveries = 0;
  double stuck_s = 0, elapsed_s = 0;
};

// Bounds on what the bus can make the page hold: whatever arrives, /api/state stays small.
struct ViewerLimits {
  double forget_after_s = 60.0;  // deputies and nodes not heard from this long are dropped
  int max_deputies = 16;         // beyond: the least recently heard is dropped
  int max_commands_per_deputy = 64;
  int max_nodes = 64;
  int max_items = 2000;      // people, sound sources, scan points, path points
  int max_text_bytes = 200;  // any string from the bus (names, keywords, messages)
  size_t max_trail = 2000;
};

// `text` cut to at most `max_bytes`, never in the middle of a UTF-8 character.
std::string ClipText(const std::string& text, size_t max_bytes);

class ViewerState {
 public:
  explicit ViewerState(ViewerLimits limits = ViewerLimits()) : limits_(limits) {}

  void SetMap(GridImage grid);
  void SetPose(common::Utime utime, double x_m, double y_m, double yaw_rad);
  void SetScan(std::vector<Eigen::Vector2d> points_map);
  void SetPeople(std::vector<PersonView> people);
  void SetSources(std::vector<SourceView> sources);
  void SetProcesses(const std::string& deputy, std::vector<ProcessView> processes, double now_s);
  void SetNode(NodeView node);
  void SetCameraJpeg(std::vector<uint8_t> jpeg);
  void SetMission(MissionView mission);

  // The whole state for the page (without the map and camera bytes, which have their own URLs
  // and a version number so the page fetches them only when they change). Deputies and nodes
  // not heard from for forget_after_s are left out; strings that are not valid UTF-8 are
  // repaired (U+FFFD), never an exception.
  std::string Json(double now_s) const;
  // The grid as a PNG (unknown grey, free white, occupied black); empty without a map.
  std::vector<uint8_t> MapPng() const;
  std::vector<uint8_t> CameraJpeg() const;

 private:
  // Drops deputies and nodes not heard from for forget_after_s (mutex_ held).
  void Forget(double now_s);
  mutable std::mutex mutex_;
  ViewerLimits limits_;
  GridImage grid_;
  int64_t map_version_ = 0;
  mutable std::vector<uint8_t> map_png_;
  mutable int64_t map_png_version_ = -1;
  common::Utime utime_ = 0;
  bool has_pose_ = false;
  double x_ = 0, y_ = 0, yaw_ = 0;
  std::deque<Eigen::Vector2d> trail_;
  std::vector<Eigen::Vector2d> scan_;
  std::vector<PersonView> people_;
  std::vector<SourceView> sources_;
  std::map<std::string, std::pair<double, std::vector<ProcessView>>>
      processes_;  // deputy -> (seen, list)
  std::map<std::string, NodeView> nodes_;
  std::vector<uint8_t> camera_;
  bool has_mission_ = false;
  MissionView mission_;
  int64_t camera_version_ = 0;
};

}  // namespace viewer
}  // namespace sarmap
