#include "log-tools/mission_metrics.h"

#include <algorithm>
#include <cmath>

#include "common/grid_geometry.h"
#include "common/image_messages.h"

namespace sarmap {
namespace logtools {
namespace {

// Yaw of a unit quaternion (w, x, y, z) about +z: atan2(2 (w z + x y), 1 - 2 (y^2 + z^2)).
double Yaw(const double (&q)[4]) {
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

bool JudgesStuck(const std::string& state) {
  return state == "exploring" || state == "seeking_sound" || state == "recovering" ||
         state == "returning";
}

}  // namespace

double TrailResidualRms(
    const common::Rigid2d& map_from_world,
    const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& estimate_truth) {
  if (estimate_truth.empty()) return 0;
  double sum = 0;
  for (const auto& [estimate, truth] : estimate_truth)
    sum += (map_from_world * truth - estimate).squaredNorm();
  return std::sqrt(sum / estimate_truth.size());
}

std::vector<int> MatchPeople(const std::vector<Eigen::Vector2d>& truth_in_map,
                             const std::vector<sarmap::mapped_person_t>& mapped, double radius_m,
                             std::vector<double>* distance_m) {
  struct Pair {
    double d;
    size_t t, f;
  };
  std::vector<Pair> pairs;
  for (size_t t = 0; t < truth_in_map.size(); ++t) {
    for (size_t f = 0; f < mapped.size(); ++f) {
      const double d = std::hypot(truth_in_map[t].x() - mapped[f].position_m[0],
                                  truth_in_map[t].y() - mapped[f].position_m[1]);
      if (d <= radius_m) pairs.push_back({d, t, f});
    }
  }
  // Stable: equal distances keep the order of the true, then the mapped, people.
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<int> truth_to(truth_in_map.size(), -1);
  std::vector<char> used(mapped.size(), 0);
  if (distance_m) distance_m->assign(truth_in_map.size(), 0.0);
  for (const auto& p : pairs) {
    if (truth_to[p.t] >= 0 || used[p.f]) continue;
    truth_to[p.t] = static_cast<int>(p.f);
    used[p.f] = 1;
    if (distance_m) (*distance_m)[p.t] = p.d;
  }
  return truth_to;
}

bool MissionMetrics::Grid::Known(const Eigen::Vector2d& p) const {
  // Cell coordinates: R(-origin_yaw) (p - origin) / resolution, floored.
  const Eigen::Vector2d q = Eigen::Rotation2Dd(-origin_yaw_rad) *
                            (p - Eigen::Vector2d(origin_x_m, origin_y_m)) / resolution_m;
  const double col = std::floor(q.x()), row = std::floor(q.y());
  if (col < 0 || row < 0 || col >= width || row >= height) return false;
  return cells[static_cast<size_t>(row) * width + static_cast<size_t>(col)] >= 0;
}

MissionMetrics::MissionMetrics(const MissionMetricsOptions& options) : options_(options) {}

double MissionMetrics::Since(int64_t utime) const {
  return first_truth_utime_ ? (utime - *first_truth_utime_) * 1e-6 : 0.0;
}

void MissionMetrics::Touch(int64_t utime) {
  last_utime_ = last_utime_ ? std::max(*last_utime_, utime) : utime;
}

void MissionMetrics::OnTruth(int64_t utime, const sarmap::sim_truth_t& truth) {
  Touch(utime);
  if (!first_truth_utime_) {
    first_truth_utime_ = utime;
    map_from_world_ =
        common::Rigid2d(truth.start_pose[0], truth.start_pose[1], truth.start_pose[2]).inverse();
  }
  truth_ = truth;
  window_.push_back({utime, Eigen::Vector2d(truth.robot_position_m[0], truth.robot_position_m[1]),
                     Yaw(truth.robot_orientation)});
  // Keep exactly one sample at or before utime - window: the window's start.
  const int64_t window_start =
      utime - static_cast<int64_t>(std::llround(options_.stuck_window_s * 1e6));
  while (window_.size() >= 2 && window_[1].utime <= window_start) window_.pop_front();
  bool stuck = false;
  if (explore_ && JudgesStuck(explore_->state) && window_.front().utime <= window_start) {
    stuck = true;
    const Sample& now = window_.back();
    for (const Sample& s : window_) {
      if ((s.position_m - now.position_m).norm() >= options_.stuck_distance_m ||
          std::abs(common::WrapAngle(s.yaw_rad - now.yaw_rad)) >= options_.stuck_turn_rad) {
        stuck = false;
        break;
      }
    }
  }
  if (stuck && was_stuck_ && window_.size() >= 2) {
    const double dt = (utime - window_[window_.size() - 2].utime) * 1e-6;
    stuck_s_ += dt;
    run_s_ += dt;
    longest_stuck_s_ = std::max(longest_stuck_s_, run_s_);
  }
  if (!stuck) run_s_ = 0;
  was_stuck_ = stuck;

  confined_window_.push_back(window_.back());
  const int64_t confined_start =
      utime - static_cast<int64_t>(std::llround(options_.confined_window_s * 1e6));
  while (confined_window_.size() >= 2 && confined_window_[1].utime <= confined_start) {
    confined_window_.pop_front();
  }
  bool confined = false;
  if (explore_ && JudgesStuck(explore_->state) &&
      confined_window_.front().utime <= confined_start) {
    confined = true;
    for (const Sample& s : confined_window_) {
      if ((s.position_m - window_.back().position_m).norm() >= options_.confined_radius_m) {
        confined = false;
        break;
      }
    }
  }
  if (!confined) {
    confined_since_utime_.reset();
  } else {
    if (!confined_since_utime_) confined_since_utime_ = confined_window_.front().utime;
    longest_confined_s_ = std::max(longest_confined_s_, (utime - *confined_since_utime_) * 1e-6);
  }
}

void MissionMetrics::OnFloor(int64_t utime, const sarmap::occupancy_grid_t& floor) {
  Touch(utime);
  std::vector<int8_t> cells;
  std::string error;
  if (floor.resolution_m <= 0 || !common::DecodeOccupancyGrid(floor, &cells, &error)) return;
  floor_world_.clear();
  const Eigen::Rotation2Dd rotation(floor.origin_yaw_rad);
  const Eigen::Vector2d origin(floor.origin_x_m, floor.origin_y_m);
  for (int row = 0; row < floor.height; ++row) {
    for (int col = 0; col < floor.width; ++col) {
      if (cells[static_cast<size_t>(row) * floor.width + col] != 0) continue;
      floor_world_.push_back(
          origin + rotation * (Eigen::Vector2d(col + 0.5, row + 0.5) * floor.resolution_m));
    }
  }
  floor_resolution_m_ = floor.resolution_m;
  floor_yaw_rad_ = floor.origin_yaw_rad;
  have_floor_ = true;
}

void MissionMetrics::OnMap(int64_t utime, const sarmap::occupancy_grid_t& map) {
  Touch(utime);
  Grid grid;
  std::string error;
  if (map.resolution_m <= 0 || !common::DecodeOccupancyGrid(map, &grid.cells, &error)) return;
  common::CopyGridGeometry(map, &grid);
  grid.origin_yaw_rad = map.origin_yaw_rad;
  map_ = std::move(grid);
  map_time_s_ = Since(utime);
  map_on_curve_ = false;
  if (!first_truth_utime_ || !have_floor_) return;
  if (coverage_.empty() || map_time_s_ - coverage_.back().time_s >= options_.coverage_interval_s) {
    AddCoveragePoint(map_time_s_);
  }
}

int64_t MissionMetrics::MappedCells() const {
  if (!first_truth_utime_ || !have_floor_ || !map_) return -1;
  int64_t n = 0;
  for (const Eigen::Vector2d& c : floor_world_) n += map_->Known(map_from_world_ * c) ? 1 : 0;
  return n;
}

void MissionMetrics::AddCoveragePoint(double t_s) {
  const int64_t n = MappedCells();
  if (n < 0) return;
  CoveragePoint p;
  p.time_s = t_s;
  p.mapped_m2 = n * floor_resolution_m_ * floor_resolution_m_;
  p.fraction = floor_world_.empty() ? 0.0 : static_cast<double>(n) / floor_world_.size();
  coverage_.push_back(p);
  map_on_curve_ = true;
}

void MissionMetrics::OnPeopleMap(int64_t utime, const sarmap::people_map_t& people) {
  Touch(utime);
  people_ = people;
  if (!truth_) return;
  std::vector<Eigen::Vector2d> truth_in_map;
  for (const auto& p : truth_->people) {
    truth_in_map.push_back(map_from_world_ * Eigen::Vector2d(p.position_m[0], p.position_m[1]));
  }
  const std::vector<int> match = MatchPeople(truth_in_map, people.people, options_.match_radius_m);
  for (size_t i = 0; i < match.size(); ++i) {
    if (match[i] < 0) continue;
    const int64_t id = truth_->people[i].id;
    const bool known = std::any_of(first_matched_s_.begin(), first_matched_s_.end(),
                                   [&](const auto& f) { return f.first == id; });
    if (!known) first_matched_s_.emplace_back(id, Since(utime));
  }
}

void MissionMetrics::OnExploreStatus(int64_t utime, const sarmap::explore_status_t& status) {
  Touch(utime);
  explore_ = status;
  if (status.state == "home" && !home_s_) home_s_ = Since(utime);
}

std::vector<Eigen::Vector2d> MissionMetrics::UnmappedFloorInMap() const {
  std::vector<Eigen::Vector2d> out;
  if (!first_truth_utime_ || !have_floor_ || !map_) return out;
  for (const Eigen::Vector2d& c : floor_world_) {
    const Eigen::Vector2d m = map_from_world_ * c;
    if (!map_->Known(m)) out.push_back(m);
  }
  return out;
}

MissionMetricsResult MissionMetrics::Result() const {
  MissionMetricsResult r;
  r.have_truth = truth_.has_value();
  r.world_from_map = map_from_world_.inverse();
  if (first_truth_utime_ && last_utime_) r.mission_s = Since(*last_utime_);
  r.coverage = coverage_;
  const int64_t n = MappedCells();
  if (n >= 0) {
    const double cell_m2 = floor_resolution_m_ * floor_resolution_m_;
    r.reachable_m2 = floor_world_.size() * cell_m2;
    r.mapped_m2 = n * cell_m2;
    r.mapped_fraction = floor_world_.empty() ? 0.0 : static_cast<double>(n) / floor_world_.size();
    if (!map_on_curve_) r.coverage.push_back({map_time_s_, *r.mapped_m2, *r.mapped_fraction});
  } else if (have_floor_) {
    r.reachable_m2 = floor_world_.size() * floor_resolution_m_ * floor_resolution_m_;
  }
  if (truth_) {
    r.distance_m = truth_->distance_m;
    r.collisions = truth_->collisions;
    std::vector<Eigen::Vector2d> truth_in_map;
    for (const auto& p : truth_->people) {
      truth_in_map.push_back(map_from_world_ * Eigen::Vector2d(p.position_m[0], p.position_m[1]));
    }
    std::vector<int> match(truth_in_map.size(), -1);
    std::vector<double> error(truth_in_map.size(), 0.0);
    if (people_)
      match = MatchPeople(truth_in_map, people_->people, options_.match_radius_m, &error);
    for (size_t i = 0; i < truth_->people.size(); ++i) {
      const auto& t = truth_->people[i];
      PersonOutcome o;
      o.truth_id = t.id;
      o.name = t.name;
      o.world_m = Eigen::Vector2d(t.position_m[0], t.position_m[1]);
      o.map_m = truth_in_map[i];
      const auto first = std::find_if(first_matched_s_.begin(), first_matched_s_.end(),
                                      [&](const auto& f) { return f.first == t.id; });
      if (match[i] >= 0) {
        const auto& p = people_->people[match[i]];
        o.found = true;
        o.person_id = p.id;
        o.cues = p.cues;
        o.error_m = error[i];
        if (first != first_matched_s_.end()) o.found_after_s = first->second;
      } else {
        o.dropped = first != first_matched_s_.end();
      }
      r.people.push_back(o);
    }
    const double home_error_m = std::hypot(truth_->robot_position_m[0] - truth_->start_pose[0],
                                           truth_->robot_position_m[1] - truth_->start_pose[1]);
    r.came_home = home_s_.has_value() && home_error_m <= options_.home_radius_m;
    r.home_error_m = home_error_m;
    if (r.came_home) r.home_after_s = home_s_;
  }
  if (explore_) {
    r.stuck_s = stuck_s_;
    r.longest_stuck_s = longest_stuck_s_;
    r.longest_confined_s = longest_confined_s_;
    r.last_explore_state = explore_->state;
  }
  return r;
}

}  // namespace logtools
}  // namespace sarmap
