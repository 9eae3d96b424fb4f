#include "viewer/viewer_state.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <iterator>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace sarmap {
namespace viewer {

Ellipse ThreeSigmaEllipse(const Eigen::Matrix2d& covariance) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (covariance + covariance.transpose()));
  const Eigen::Vector2d values = eig.eigenvalues().cwiseMax(0.0);  // ascending
  Ellipse e;
  e.major_m = 3.0 * std::sqrt(values(1));
  e.minor_m = 3.0 * std::sqrt(values(0));
  const Eigen::Vector2d axis = eig.eigenvectors().col(1);
  e.angle_rad = std::atan2(axis.y(), axis.x());
  return e;
}

std::string ClipText(const std::string& text, size_t max_bytes) {
  if (text.size() <= max_bytes) return text;
  size_t n = max_bytes;
  // Back off over UTF-8 continuation bytes (10xxxxxx) so a character is never split.
  while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;
  return text.substr(0, n);
}

void ViewerState::SetMap(GridImage grid) {
  std::lock_guard<std::mutex> lock(mutex_);
  grid_ = std::move(grid);
  ++map_version_;
}

void ViewerState::SetPose(common::Utime utime, double x_m, double y_m, double yaw_rad) {
  std::lock_guard<std::mutex> lock(mutex_);
  utime_ = utime;
  has_pose_ = true;
  x_ = x_m;
  y_ = y_m;
  yaw_ = yaw_rad;
  if (trail_.empty() || (trail_.back() - Eigen::Vector2d(x_m, y_m)).norm() > 0.05) {
    trail_.emplace_back(x_m, y_m);
    if (trail_.size() > limits_.max_trail) trail_.pop_front();
  }
}

void ViewerState::SetScan(std::vector<Eigen::Vector2d> points_map) {
  std::lock_guard<std::mutex> lock(mutex_);
  scan_ = std::move(points_map);
  if (scan_.size() > static_cast<size_t>(limits_.max_items)) scan_.resize(limits_.max_items);
}

void ViewerState::SetPeople(std::vector<PersonView> people) {
  std::lock_guard<std::mutex> lock(mutex_);
  people_ = std::move(people);
  if (people_.size() > static_cast<size_t>(limits_.max_items)) people_.resize(limits_.max_items);
  for (auto& p : people_) p.keyword = ClipText(p.keyword, limits_.max_text_bytes);
}

void ViewerState::SetSources(std::vector<SourceView> sources) {
  std::lock_guard<std::mutex> lock(mutex_);
  sources_ = std::move(sources);
  if (sources_.size() > static_cast<size_t>(limits_.max_items)) sources_.resize(limits_.max_items);
  for (auto& s : sources_) s.state = ClipText(s.state, limits_.max_text_bytes);
}

namespace {

// Makes room for one more key in `entries` (at most `max`): drops the least recently heard.
template <class Map, class SeenOf>
void MakeRoom(Map* entries, const std::string& key, size_t max, SeenOf seen_of) {
  if (entries->count(key) || entries->size() < max) return;
  while (!entries->empty() && entries->size() >= max) {
    auto oldest = entries->begin();
    for (auto it = entries->begin(); it != entries->end(); ++it) {
      if (seen_of(it->second) < seen_of(oldest->second)) oldest = it;
    }
    entries->erase(oldest);
  }
}

}  // namespace

void ViewerState::Forget(double now_s) {
  for (auto it = processes_.begin(); it != processes_.end();) {
    it = now_s - it->second.first > limits_.forget_after_s ? processes_.erase(it) : std::next(it);
  }
  for (auto it = nodes_.begin(); it != nodes_.end();) {
    it = now_s - it->second.last_seen_s > limits_.forget_after_s ? nodes_.erase(it) : std::next(it);
  }
}

void ViewerState::SetProcesses(const std::string& deputy, std::vector<ProcessView> processes,
                               double now_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  Forget(now_s);
  const std::string name = ClipText(deputy, limits_.max_text_bytes);
  if (processes.size() > static_cast<size_t>(limits_.max_commands_per_deputy)) {
    processes.resize(limits_.max_commands_per_deputy);
  }
  for (auto& p : processes) {
    p.command = ClipText(p.command, limits_.max_text_bytes);
    p.state = ClipText(p.state, limits_.max_text_bytes);
  }
  MakeRoom(&processes_, name, limits_.max_deputies, [](const auto& e) { return e.first; });
  processes_[name] = {now_s, std::move(processes)};
}

void ViewerState::SetNode(NodeView node) {
  std::lock_guard<std::mutex> lock(mutex_);
  Forget(node.last_seen_s);
  node.name = ClipText(node.name, limits_.max_text_bytes);
  node.message = ClipText(node.message, limits_.max_text_bytes);
  MakeRoom(&nodes_, node.name, limits_.max_nodes, [](const NodeView& n) { return n.last_seen_s; });
  nodes_[node.name] = node;
}

void ViewerState::SetCameraJpeg(std::vector<uint8_t> jpeg) {
  std::lock_guard<std::mutex> lock(mutex_);
  camera_ = std::move(jpeg);
  ++camera_version_;
}

namespace {

nlohmann::json EllipseJson(const Ellipse& e) {
  return {{"major_m", e.major_m}, {"minor_m", e.minor_m}, {"angle_rad", e.angle_rad}};
}

double Round(double v, double step) { return std::round(v / step) * step; }

}  // namespace

void ViewerState::SetMission(MissionView mission) {
  std::lock_guard<std::mutex> lock(mutex_);
  mission_ = std::move(mission);
  if (mission_.path.size() > static_cast<size_t>(limits_.max_items))
    mission_.path.resize(limits_.max_items);
  for (auto* text : {&mission_.state, &mission_.driven_by, &mission_.goal_kind}) {
    *text = ClipText(*text, limits_.max_text_bytes);
  }
  has_mission_ = true;
}

std::string ViewerState::Json(double now_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json j;
  j["utime"] = utime_;
  j["map"] = {{"available", grid_.width > 0},
              {"version", map_version_},
              {"width", grid_.width},
              {"height", grid_.height},
              {"resolution_m", grid_.resolution_m},
              {"origin_x_m", grid_.origin_x_m},
              {"origin_y_m", grid_.origin_y_m}};
  if (has_pose_) j["robot"] = {{"x_m", x_}, {"y_m", y_}, {"yaw_rad", yaw_}};
  j["trail"] = nlohmann::json::array();
  for (const auto& p : trail_) j["trail"].push_back({Round(p.x(), 0.01), Round(p.y(), 0.01)});
  j["scan"] = nlohmann::json::array();
  for (const auto& p : scan_) j["scan"].push_back({Round(p.x(), 0.01), Round(p.y(), 0.01)});
  j["people"] = nlohmann::json::array();
  for (const auto& p : people_) {
    std::string cue = p.seen && p.heard ? "both" : p.heard ? "heard" : "seen";
    j["people"].push_back({{"id", p.id},
                           {"x_m", p.x_m},
                           {"y_m", p.y_m},
                           {"ellipse", EllipseJson(p.ellipse)},
                           {"confidence", p.confidence},
                           {"cue", cue},
                           {"depth_only", p.seen_depth_only},
                           {"count", p.count},
                           {"keyword", p.keyword}});
  }
  j["sources"] = nlohmann::json::array();
  for (const auto& s : sources_) {
    j["sources"].push_back({{"id", s.id},
                            {"x_m", s.x_m},
                            {"y_m", s.y_m},
                            {"ellipse", EllipseJson(s.ellipse)},
                            {"state", s.state},
                            {"is_person", s.is_person},
                            {"sound_class", s.sound_class},
                            {"calling", s.calling},
                            {"has_position", s.has_position},
                            {"bearing_rad", s.bearing_rad},
                            {"bearing_sigma_rad", s.bearing_sigma_rad}});
  }
  j["processes"] = nlohmann::json::array();
  for (const auto& [deputy, entry] : processes_) {
    if (now_s - entry.first > limits_.forget_after_s) continue;
    const bool lost = now_s - entry.first > 3.0;
    for (const auto& p : entry.second) {
      j["processes"].push_back({{"deputy", deputy},
                                {"command", p.command},
                                {"state", lost ? "deputy lost" : p.state},
                                {"pid", p.pid},
                                {"restarts", p.restarts},
                                {"cpu_percent", Round(p.cpu_percent, 0.1)},
                                {"rss_mb", Round(p.rss_mb, 0.1)}});
    }
  }
  j["nodes"] = nlohmann::json::array();
  for (const auto& [name, n] : nodes_) {
    if (now_s - n.last_seen_s > limits_.forget_after_s) continue;
    j["nodes"].push_back({{"name", name},
                          {"dropped", n.dropped},
                          {"message", n.message},
                          {"age_s", Round(now_s - n.last_seen_s, 0.1)}});
  }
  j["camera"] = {{"available", !camera_.empty()}, {"version", camera_version_}};
  if (has_mission_) {
    nlohmann::json path = nlohmann::json::array();
    for (const auto& p : mission_.path) path.push_back({Round(p.x(), 0.01), Round(p.y(), 0.01)});
    j["mission"] = {{"state", mission_.state},
                    {"driven_by", mission_.driven_by},
                    {"goal_kind", mission_.goal_kind},
                    {"has_goal", mission_.has_goal},
                    {"goal", {Round(mission_.goal_x_m, 0.01), Round(mission_.goal_y_m, 0.01)}},
                    {"path", path},
                    {"frontiers", mission_.frontiers},
                    {"recoveries", mission_.recoveries},
                    {"stuck_s", Round(mission_.stuck_s, 0.1)},
                    {"elapsed_s", Round(mission_.elapsed_s, 0.1)}};
  }
  // Strings come from the bus: invalid UTF-8 is replaced, not thrown about.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::vector<uint8_t> ViewerState::MapPng() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (grid_.width == 0) return {};
  if (map_png_version_ == map_version_) return map_png_;
  // Row 0 of the grid is at the origin (bottom of the picture): flip vertically.
  cv::Mat image(grid_.height, grid_.width, CV_8UC1);
  for (int y = 0; y < grid_.height; ++y) {
    uint8_t* row = image.ptr<uint8_t>(grid_.height - 1 - y);
    for (int x = 0; x < grid_.width; ++x) {
      const int8_t v = grid_.cells[static_cast<size_t>(y) * grid_.width + x];
      row[x] = v < 0 ? 205 : static_cast<uint8_t>(255 - v * 255 / 100);
    }
  }
  cv::imencode(".png", image, map_png_);
  map_png_version_ = map_version_;
  return map_png_;
}

std::vector<uint8_t> ViewerState::CameraJpeg() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return camera_;
}

}  // namespace viewer
}  // namespace sarmap
