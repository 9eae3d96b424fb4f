#include "viewer/viewer_messages.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace viewer {
namespace {

// The 3-sigma ellipse of the x-y block of a row-major 3x3 covariance.
Ellipse EllipseOf(const double* covariance3) {
  Eigen::Matrix2d cov;
  cov << covariance3[0], covariance3[1], covariance3[3], covariance3[4];
  return ThreeSigmaEllipse(cov);
}

// Where a mapped person or sound source is: its id, x-y position and 3-sigma ellipse.
template <class Message, class View>
void SetPlace(const Message& m, View* v) {
  v->id = m.id;
  v->x_m = m.position_m[0];
  v->y_m = m.position_m[1];
  v->ellipse = EllipseOf(m.covariance);
}

}  // namespace

std::vector<PersonView> PeopleViews(const people_map_t& m) {
  std::vector<PersonView> people;
  for (const auto& p : m.people) {
    PersonView v;
    SetPlace(p, &v);
    v.confidence = p.confidence;
    v.seen = p.cues & (mapped_person_t::CUE_SEEN_RGBD | mapped_person_t::CUE_SEEN_DEPTH);
    v.seen_depth_only =
        (p.cues & mapped_person_t::CUE_SEEN_DEPTH) && !(p.cues & mapped_person_t::CUE_SEEN_RGBD);
    v.heard = p.cues & mapped_person_t::CUE_HEARD;
    v.count = p.people_count;
    v.keyword = p.keyword;
    people.push_back(v);
  }
  return people;
}

std::vector<SourceView> SourceViews(const sound_map_t& m) {
  static const char* kClasses[] = {"unknown", "voice", "alarm", "machinery", "music"};
  std::vector<SourceView> sources;
  for (const auto& s : m.sources) {
    SourceView v;
    SetPlace(s, &v);
    v.state = s.state == sound_source_t::STATE_CONVERGED ? "converged"
              : s.state == sound_source_t::STATE_SILENT  ? "silent"
                                                         : "initialising";
    v.is_person = s.is_person;
    v.sound_class = s.sound_class >= 0 && s.sound_class <= 4 ? kClasses[s.sound_class] : "unknown";
    v.calling = s.priority == sound_source_t::PRIORITY_CALL;
    v.has_position = s.has_position;
    v.bearing_rad = s.bearing_rad;
    v.bearing_sigma_rad = std::sqrt(std::max(0.0, s.bearing_variance));
    sources.push_back(v);
  }
  return sources;
}

std::vector<ProcessView> ProcessViews(const pm_info_t& m) {
  static const char* kStates[] = {"stopped",  "starting", "running",
                                  "stopping", "failed",   "respawning"};
  std::vector<ProcessView> processes;
  for (const auto& c : m.commands) {
    ProcessView p;
    p.command = c.command_id;
    p.state = c.state >= 0 && c.state <= 5 ? kStates[c.state] : "?";
    p.pid = c.pid;
    p.restarts = c.restart_count;
    p.cpu_percent = c.cpu_percent;
    p.rss_mb = c.rss_bytes / 1e6;
    processes.push_back(p);
  }
  return processes;
}

NodeView NodeViewOf(const node_status_t& m, double now_s) {
  NodeView v;
  v.name = m.node_name;
  v.message = m.message;
  for (const auto& c : m.channels) v.dropped += c.dropped_malformed;
  v.last_seen_s = now_s;
  return v;
}

MissionView MissionViewOf(const explore_status_t& m) {
  MissionView v;
  v.state = m.state;
  v.driven_by = m.driven_by;
  v.goal_kind = m.goal_kind;
  v.has_goal = m.has_goal;
  v.goal_x_m = m.goal_m[0];
  v.goal_y_m = m.goal_m[1];
  for (size_t i = 0; i < m.path_x_m.size() && i < m.path_y_m.size(); ++i) {
    v.path.emplace_back(m.path_x_m[i], m.path_y_m[i]);
  }
  v.frontiers = m.frontiers;
  v.recoveries = m.recoveries;
  v.stuck_s = m.stuck_s;
  v.elapsed_s = m.elapsed_s;
  return v;
}

std::vector<Eigen::Vector2d> ScanPointsInMap(const laser_scan_t& m,
                                             const common::Rigid2d& map_from_base) {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i < m.num_ranges && i < static_cast<int>(m.ranges_m.size()); ++i) {
    const double r = m.ranges_m[i];
    if (!std::isfinite(r) || r < m.range_min_m || r > m.range_max_m) continue;
    const double a = m.angle_min_rad + i * m.angle_increment_rad;
    points.push_back(map_from_base * Eigen::Vector2d(r * std::cos(a), r * std::sin(a)));
  }
  return points;
}

}  // namespace viewer
}  // namespace sarmap
