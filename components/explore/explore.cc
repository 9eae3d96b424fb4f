#include "explore/explore.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_set>

#include "common/logging.h"

namespace sarmap {
namespace explore {

namespace {

bool NoInformation(float r, const Scan& scan) {
  return !(r > 0) || (std::isfinite(r) && r < scan.range_min_m);  // 0, NaN, negative, too close
}

}  // namespace

ScanMetrics AnalyseScan(const Scan& scan, const ReactiveOptions& options) {
  ScanMetrics m;
  m.min_valid_m = std::numeric_limits<double>::infinity();
  double sum_left = 0, sum_right = 0;
  int n_left = 0, n_right = 0, unknown_left = 0, unknown_right = 0;
  const double upper = scan.range_max_m - options.max_range_margin_m;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double angle = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const bool left = angle > 0;
    double r = scan.ranges_m[i];
    (left ? n_left : n_right)++;
    // No return (+inf) is free space up to the sensor's range, not an unknown.
    if (std::isinf(r) && r > 0) r = scan.range_max_m;
    const bool no_return = r == scan.range_max_m && std::isinf(scan.ranges_m[i]);
    const bool valid = no_return || (std::isfinite(r) && r >= scan.range_min_m && r <= upper);
    if (!valid) {
      (left ? unknown_left : unknown_right)++;
      continue;
    }
    m.min_valid_m = std::min(m.min_valid_m, r);
    (left ? sum_left : sum_right) += r;
  }
  const int n = n_left + n_right;
  m.unknown_rate = n > 0 ? static_cast<double>(unknown_left + unknown_right) / n : 1.0;
  m.unknown_left = n_left > 0 ? static_cast<double>(unknown_left) / n_left : 1.0;
  m.unknown_right = n_right > 0 ? static_cast<double>(unknown_right) / n_right : 1.0;
  m.mean_left_m = n_left > unknown_left ? sum_left / (n_left - unknown_left) : 0.0;
  m.mean_right_m = n_right > unknown_right ? sum_right / (n_right - unknown_right) : 0.0;
  return m;
}

Velocity ReactiveExplorer::Step(const Scan& scan, bool* danger) {
  const ScanMetrics m = AnalyseScan(scan, options_);
  const bool in_danger =
      m.min_valid_m < options_.danger_distance_m || m.unknown_rate >= options_.unknown_rate_limit;
  if (danger) *danger = in_danger;
  Velocity v;
  v.source = "reactive";
  if (!in_danger) {
    turning_ = 0;
    v.linear_mps = options_.forward_speed_mps;
    return v;
  }
  if (turning_ == 0) {  // choose a side once, then keep it until the way is clear
    if (m.mean_left_m < options_.low_average_m && m.mean_right_m < options_.low_average_m) {
      turning_ = m.unknown_left >= m.unknown_right ? 1 : -1;
    } else {
      turning_ = m.mean_left_m >= m.mean_right_m ? 1 : -1;
    }
  }
  v.angular_radps = turning_ * options_.turn_speed_radps;
  return v;
}

double ScanClearanceAhead(const Scan& scan, const SafetyOptions& options) {
  double clearance = std::numeric_limits<double>::infinity();
  const double cone = std::atan2(options.corridor_half_width_m, options.stop_distance_m);
  int in_cone = 0, blind = 0;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double a = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const float r = scan.ranges_m[i];
    if (std::abs(a) <= cone) {
      ++in_cone;
      if (NoInformation(r, scan)) ++blind;
    }
    if (!std::isfinite(r) || NoInformation(r, scan)) continue;
    const double x = r * std::cos(a), y = r * std::sin(a);
    if (x > 0 && std::abs(y) <= options.corridor_half_width_m) clearance = std::min(clearance, x);
  }
  // Columns without information straight ahead: something nearer than the camera can see.
  if (in_cone > 0 && blind > options.blind_fraction * in_cone) return 0.0;
  return clearance;
}

ExploreController::ExploreController(const ExploreOptions& options)
    : options_(options),
      reactive_(options.reactive),
      map_(options.planner),
      local_obstacles_(options.safety.memory_s, options.safety.memory_radius_m) {
  if (!options_.goals.look_around) state_ = State::kExploring;
}

const char* ExploreController::StateName(State s) {
  switch (s) {
    case State::kLookAround:
      return "look_around";
    case State::kExploring:
      return "exploring";
    case State::kSeekingSound:
      return "seeking_sound";
    case State::kSweeping:
      return "sweeping";
    case State::kRecovering:
      return "recovering";
    case State::kReturning:
      return "returning";
    case State::kHome:
      return "home";
    case State::kFinished:
      return "finished";
  }
  return "?";
}

void ExploreController::OnMap(const Grid& grid) {
  map_.SetMap(grid);
  map_changed_ = true;
}

void ExploreController::OnPose(const common::Rigid2d& map_from_base, double stamp_s) {
  pose_stamp_s_ = stamp_s;
  if (pose_ && state_ == State::kLookAround) {
    look_turned_rad_ +=
        std::abs(common::WrapAngle(map_from_base.yaw_rad() - pose_->yaw_rad()));
  }
  pose_ = map_from_base;
  if (!home_) home_ = map_from_base.translation();
  map_.AddTrail(map_from_base.translation());
}

void ExploreController::OnOdometry(const common::Rigid2d& odom_from_base, double stamp_s) {
  // A clock that steps back starts the history again.
  if (!odometry_.empty() && stamp_s < odometry_.back().first) odometry_.clear();
  odometry_.emplace_back(stamp_s, odom_from_base);
  while (odometry_.size() > 2 && odometry_.front().first < stamp_s - 1.0) odometry_.pop_front();
}

std::optional<common::Rigid2d> ExploreController::OdometryAt(double stamp_s) const {
  // Odometry more than this older than the scan is not the robot's motion up to the scan.
  constexpr double kMaxAgeS = 0.5;
  if (odometry_.empty() || odometry_.back().first < stamp_s - kMaxAgeS) return std::nullopt;
  if (stamp_s >= odometry_.back().first) return odometry_.back().second;
  if (stamp_s <= odometry_.front().first) return odometry_.front().second;
  for (size_t i = 1; i < odometry_.size(); ++i) {
    const auto& [t1, b] = odometry_[i];
    if (t1 < stamp_s) continue;
    const auto& [t0, a] = odometry_[i - 1];
    const double f = t1 > t0 ? (stamp_s - t0) / (t1 - t0) : 1.0;
    return common::Interpolate(a, b, f);
  }
  return odometry_.back().second;
}

bool ExploreController::ArcApproachesMemory(double linear_mps, double angular_radps) const {
  const SafetyOptions& o = options_.safety;
  if (local_points_.empty() || o.sweep_horizon_s <= 0) return false;
  const double nearest_now = NearestDistance(Eigen::Vector2d::Zero(), local_points_);
  for (int k = 1; k <= 6; ++k) {
    const double t = o.sweep_horizon_s * k / 6;
    const double mean_yaw = 0.5 * angular_radps * t;
    const Eigen::Vector2d p =
        linear_mps * t * Eigen::Vector2d(std::cos(mean_yaw), std::sin(mean_yaw));
    const double nearest_then = NearestDistance(p, local_points_);
    if (nearest_then < o.footprint_radius_m && nearest_then < nearest_now - 1e-3) return true;
  }
  return false;
}

std::optional<Eigen::Vector2d> ExploreController::UnseenOnArc(const Velocity& desired,
                                                              const Scan& scan) const {
  const SafetyOptions& o = options_.safety;
  if (o.unseen_lookahead_m <= 0 || desired.linear_mps <= 0 || !map_.has_map() || !pose_ ||
      scan.ranges_m.empty()) {
    return std::nullopt;
  }
  const Grid& grid = map_.grid();
  const double res = grid.resolution_m;
  const double last_beam_rad =
      scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(scan.ranges_m.size() - 1);
  const double fov_min = std::min(scan.angle_min_rad, last_beam_rad);
  const double fov_max = std::max(scan.angle_min_rad, last_beam_rad);
  // The arc of constant curvature k = w / v: after s metres the base is at
  // (sin(k s) / k, (1 - cos(k s)) / k), heading k s, in its present frame.
  const double k = desired.angular_radps / desired.linear_mps;
  std::vector<common::Rigid2d> arc;  // base poses every cell along the arc, present frame
  for (double s = 0; s <= o.unseen_lookahead_m + 1e-9; s += res) {
    arc.push_back(std::abs(k) < 1e-6
                      ? common::Rigid2d(s, 0.0, 0.0)
                      : common::Rigid2d(std::sin(k * s) / k, (1 - std::cos(k * s)) / k, k * s));
  }
  const auto in_view = [&](const common::Rigid2d& from, const Eigen::Vector2d& p) {
    const Eigen::Vector2d q = from.inverse() * p;
    const double bearing = std::atan2(q.y(), q.x());
    return q.norm() >= scan.range_min_m && bearing >= fov_min && bearing <= fov_max;
  };
  const int reach = static_cast<int>(std::ceil(o.footprint_radius_m / res));
  std::unordered_set<int> checked;  // cells already met nearer along the arc
  std::optional<Eigen::Vector2d> nearest;
  double nearest_m = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i < arc.size(); ++i) {
    const Eigen::Vector2i c = grid.CellOf(*pose_ * arc[i].translation());
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const int x = c.x() + dx, y = c.y() + dy;
        if (!grid.Contains(x, y) || map_.Seen(x, y)) continue;
        const int index = grid.Index(x, y);
        if (checked.count(index) > 0) continue;
        const Eigen::Vector2d local = pose_->inverse() * grid.CentreOf(x, y);
        if ((local - arc[i].translation()).norm() > o.footprint_radius_m) continue;
        checked.insert(index);  // first swept at arc[i]
        // Under the base already, or nearer than the sensor sees: turning shows nothing.
        const double range_m = local.norm();
        if (range_m <= o.footprint_radius_m || range_m < scan.range_min_m) continue;
        // The sensor sees it from the arc before the base gets there.
        bool seen_on_the_way = false;
        for (size_t j = 0; j < i && !seen_on_the_way; ++j) seen_on_the_way = in_view(arc[j], local);
        if (seen_on_the_way || range_m >= nearest_m) continue;
        nearest_m = range_m;
        nearest = grid.CentreOf(x, y);
      }
    }
  }
  return nearest;
}

bool ExploreController::IsBlacklisted(const Eigen::Vector2d& p, double now_s) const {
  for (const auto& b : blacklist_) {
    if (b.until_s > now_s && (b.position_m - p).norm() < options_.goals.blacklist_radius_m)
      return true;
  }
  return false;
}

void ExploreController::GiveUpGoal(double now_s) {
  if (goal_ && goal_->kind == "sweep") {
    visited_cells_[SweepCell(goal_->position_m)] = now_s;  // not reachable now: it waits its turn
  } else if (goal_ && goal_->kind != "home") {
    blacklist_.push_back({goal_->position_m, now_s + options_.goals.blacklist_expiry_s});
    if (goal_->kind == "sound") visited_sound_.push_back(goal_->face_m.value_or(goal_->position_m));
  }
  goal_.reset();
  path_.clear();
  goal_recoveries_ = 0;
  dwell_until_s_.reset();
}

std::optional<ExploreController::Goal> ExploreController::ChooseFrontier(
    const CostField& field, const std::vector<Frontier>& frontiers) const {
  std::optional<Goal> best;
  const double yaw = pose_->yaw_rad();
  for (const Frontier& f : frontiers) {
    const Eigen::Vector2d d = f.goal_m - pose_->translation();
    const double turn =
        d.norm() > 1e-3 ? std::abs(common::WrapAngle(std::atan2(d.y(), d.x()) - yaw)) : 0.0;
    Goal g;
    g.position_m = f.goal_m;
    g.kind = "frontier";
    g.face_m = f.centroid_m;
    g.score = f.path_cost_m - options_.goals.size_weight * std::min(f.size_m, 4.0) +
              options_.goals.heading_weight_m * turn / M_PI;
    if (!best || g.score < best->score) best = g;
  }
  (void)field;
  return best;
}

std::optional<ExploreController::Goal> ExploreController::ChooseSoundGoal(
    const CostField& field) const {
  const SoundGoalOptions& o = options_.sound;
  const Grid& grid = map_.grid();
  std::optional<Goal> best;
  // People heard and not seen, then the voices nobody on PEOPLE_MAP explains.
  std::vector<std::pair<HeardPerson, bool>> candidates;  // (target, is a SOUND_MAP voice)
  for (const HeardPerson& person : heard_) candidates.emplace_back(person, false);
  if (o.voices) {
    for (const HeardPerson& voice : voices_) {
      bool explained = false;
      for (const Eigen::Vector2d& p : people_m_)
        explained |= (p - voice.position_m).norm() < o.seen_radius_m;
      if (!explained) candidates.emplace_back(voice, true);
    }
  }
  for (const auto& [person, is_voice] : candidates) {
    if (person.seen || person.position_std_m > o.max_position_std_m) continue;
    bool visited = false;
    for (const auto& v : visited_sound_)
      visited |= (v - person.position_m).norm() < o.revisit_radius_m;
    if (visited) continue;
    const Eigen::Vector2i c = grid.CellOf(person.position_m);
    const int r = static_cast<int>(std::ceil(o.max_view_m / grid.resolution_m));
    // The cheapest cell in view of them (the person's own body, within 0.5 m of their position,
    // does not block the view); else, for someone behind cover, the cheapest cell in range: the
    // microphones still gain parallax there.
    double best_cost = std::numeric_limits<double>::infinity(), cover_cost = best_cost;
    Eigen::Vector2d best_cell = Eigen::Vector2d::Zero(), cover_cell = best_cell;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const int x = c.x() + dx, y = c.y() + dy;
        if (!grid.Contains(x, y)) continue;
        const int i = grid.Index(x, y);
        if (!field.Reached(i) || field.cost[i] >= std::max(best_cost, cover_cost)) continue;
        const Eigen::Vector2d p = grid.CentreOf(x, y);
        const double dist = (p - person.position_m).norm();
        if (dist < o.min_view_m || dist > o.max_view_m) continue;
        const Eigen::Vector2d body_edge =
            person.position_m + (p - person.position_m).normalized() * 0.5;
        if (field.cost[i] < best_cost && map_.LineOfSight(p, body_edge)) {
          best_cost = field.cost[i];
          best_cell = p;
        } else if (field.cost[i] < cover_cost) {
          cover_cost = field.cost[i];
          cover_cell = p;
        }
      }
    }
    if (!std::isfinite(best_cost)) {
      best_cost = cover_cost;
      best_cell = cover_cell;
    }
    if (!std::isfinite(best_cost) || best_cost > o.max_detour_m) continue;
    if (!best || best_cost < best->score) {
      Goal g;
      g.position_m = best_cell;
      g.kind = "sound";
      g.score = best_cost;
      g.person_id = person.id;
      g.voice = is_voice;
      g.face_m = person.position_m;
      best = g;
    }
  }
  return best;
}

std::pair<int, int> ExploreController::SweepCell(const Eigen::Vector2d& p) const {
  const double cell = options_.goals.sweep_cell_m;
  return {static_cast<int>(std::floor(p.x() / cell)), static_cast<int>(std::floor(p.y() / cell))};
}

void ExploreController::MarkVisited(double now_s) {
  if (pose_) visited_cells_[SweepCell(pose_->translation())] = now_s;
}

std::optional<ExploreController::Goal> ExploreController::ChooseSweepGoal(
    double now_s, const CostField& field) const {
  const Grid& g = map_.grid();
  const double cell = options_.goals.sweep_cell_m;
  const double start_s = start_s_ ? *start_s_ : 0.0;
  // One candidate per sweep cell: among its reached grid cells with room to stand (the
  // planner's preferred clearance, and beyond where the safety layer stops the robot short of a
  // wall), the one with the most room (up to 0.3 m more), then nearest the cell's centre; scored
  // by the time since the cell's last visit minus the drive there.
  struct Candidate {
    Eigen::Vector2d position_m;
    double room_m, from_centre_m, cost;
  };
  const double needed_room_m =
      std::max(options_.planner.robot_radius_m + options_.planner.clearance_m,
               options_.safety.stop_distance_m + 0.1);
  const double enough_room_m = needed_room_m + 0.3;
  std::map<std::pair<int, int>, Candidate> best;
  for (int i = 0; i < static_cast<int>(field.cost.size()); ++i) {
    if (!field.Reached(i)) continue;
    const int x = i % g.width, y = i / g.width;
    const Eigen::Vector2d c = g.CentreOf(x, y);
    const std::pair<int, int> key = SweepCell(c);
    const Eigen::Vector2d centre((key.first + 0.5) * cell, (key.second + 0.5) * cell);
    const double room_m = map_.Clearance(x, y);
    if (room_m < needed_room_m) continue;
    const Candidate candidate{c, std::min(room_m, enough_room_m), (c - centre).norm(),
                              field.cost[i]};
    auto it = best.find(key);
    if (it == best.end() || candidate.room_m > it->second.room_m + 1e-9 ||
        (candidate.room_m > it->second.room_m - 1e-9 &&
         candidate.from_centre_m < it->second.from_centre_m)) {
      best[key] = candidate;
    }
  }
  // Cells visited within sweep_min_age_s wait; when every cell does, any but the robot's own.
  const std::pair<int, int> here = SweepCell(pose_->translation());
  for (const double min_age_s : {options_.goals.sweep_min_age_s, 0.0}) {
    std::optional<Goal> goal;
    for (const auto& [key, candidate] : best) {
      const auto visited = visited_cells_.find(key);
      const double age_s = now_s - (visited == visited_cells_.end() ? start_s : visited->second);
      if (age_s < min_age_s || key == here) continue;
      const double score = age_s - candidate.cost / options_.goals.return_speed_mps;
      if (!goal || score > goal->score) {
        Goal next;
        next.position_m = candidate.position_m;
        next.kind = "sweep";
        next.score = score;
        goal = next;
      }
    }
    if (goal) return goal;
  }
  return std::nullopt;
}

bool ExploreController::TimeToGoHome(double now_s, const CostField& field) const {
  if (options_.goals.time_budget_s <= 0 || !start_s_ || !home_) return false;
  const Eigen::Vector2i h = map_.grid().CellOf(*home_);
  double home_cost = (pose_->translation() - *home_).norm() * 1.5;
  if (map_.grid().Contains(h.x(), h.y()) && field.Reached(map_.grid().Index(h.x(), h.y()))) {
    home_cost = field.cost[map_.grid().Index(h.x(), h.y())];
  }
  // Reserve the way home at the assumed speed, plus time to turn and settle.
  return now_s - *start_s_ + home_cost / options_.goals.return_speed_mps + 15.0 >=
         options_.goals.time_budget_s;
}

void ExploreController::Replan(double now_s) {
  last_plan_s_ = now_s;
  MarkVisited(now_s);
  map_changed_ = false;
  map_.UpdateCostMap();
  const CostField field = map_.Plan(pose_->translation());
  shut_in_ = true;
  if (!field.valid) {
    // No traversable cell near the robot (pressed against an obstacle, or the map shifted
    // under it): nothing can be concluded; the stuck detector gets it out.
    path_.clear();
    return;
  }
  // Cut off from most of the places the robot has driven through means it is shut in: by a
  // contact marked in a doorway (it came in that way; forget the contacts around it), or by a
  // doorway the map draws too narrow for now. Either way nothing is concluded from this plan (it
  // does not count towards the end of exploration). Space it has never been in (a hall seen through
  // glass) does not count.
  if (map_.TrailReachedFraction(field, options_.planner.robot_radius_m + 0.05) < 0.5) {
    if (map_.ClearContactsBounding(field)) last_plan_s_ = -1e9;
    path_.clear();
    return;
  }
  shut_in_ = false;
  shut_in_recoveries_ = 0;
  std::vector<Frontier> frontiers = map_.Frontiers(field);
  frontiers.erase(std::remove_if(frontiers.begin(), frontiers.end(),
                                 [&](const Frontier& f) { return IsBlacklisted(f.goal_m, now_s); }),
                  frontiers.end());
  frontier_count_ = static_cast<int>(frontiers.size());
  blacklist_.erase(std::remove_if(blacklist_.begin(), blacklist_.end(),
                                  [&](const BlacklistEntry& b) { return b.until_s <= now_s; }),
                   blacklist_.end());

  const bool going_home = state_ == State::kReturning;
  if (!going_home && options_.goals.return_home && TimeToGoHome(now_s, field)) {
    state_ = State::kReturning;
    returning_explored_ = false;
    goal_.reset();
  }
  if (state_ == State::kReturning && returning_explored_) {
    // Exploration ended because no plan reached a frontier; frontiers reached again on the way
    // home (SLAM re-rendered a doorway, the robot left a place the inflated map drew too
    // narrow) mean the site is not done: explore again once two plans in a row agree.
    frontier_plans_returning_ = frontiers.empty() ? 0 : frontier_plans_returning_ + 1;
    if (frontier_plans_returning_ >= 2) {
      state_ = State::kExploring;
      returning_explored_ = false;
      frontier_plans_returning_ = 0;
      empty_plans_ = 0;
      goal_.reset();
    }
  }
  if (state_ == State::kReturning) {
    if (!options_.goals.return_home || !home_) {
      state_ = State::kFinished;
      goal_.reset();
      path_.clear();
      return;
    }
    Goal home;
    home.position_m = *home_;
    home.kind = "home";
    goal_ = home;
    path_ = map_.PathTo(field, *home_);
    if (path_.empty()) {
      // Home not reachable on the current map: the nearest reached cell to it.
      double best = std::numeric_limits<double>::infinity();
      const Grid& g = map_.grid();
      for (int i = 0; i < static_cast<int>(field.cost.size()); ++i) {
        if (!field.Reached(i)) continue;
        const double d = (g.CentreOf(i % g.width, i / g.width) - *home_).norm();
        if (d < best) {
          best = d;
          goal_->position_m = g.CentreOf(i % g.width, i / g.width);
        }
      }
      path_ = map_.PathTo(field, goal_->position_m);
    }
    return;
  }

  // A heard, unseen person pre-empts the frontiers (sound-guided search).
  if (options_.mode == "sound_guided") {
    const auto sound = ChooseSoundGoal(field);
    const bool seeking = goal_ && goal_->kind == "sound";
    // The sound map renumbers a source it re-places (a voice the bearings' crossing places
    // replaces the EKF's), so a voice is also the one it was when it stays where it was.
    const auto same_target = [this](const Goal& a, const Goal& b) {
      if (a.voice != b.voice) return false;
      return a.person_id == b.person_id ||
             (a.voice && (*a.face_m - *b.face_m).norm() < options_.sound.revisit_radius_m);
    };
    const bool new_target = sound && (!seeking || !same_target(*sound, *goal_));
    if (new_target || (sound && sound->score < goal_->score - 2.0)) {
      if (new_target) {
        SARMAP_LOG(INFO) << "seeking " << (sound->voice ? "voice " : "person ") << sound->person_id
                         << " at (" << sound->face_m->x() << ", " << sound->face_m->y()
                         << ") from (" << sound->position_m.x() << ", " << sound->position_m.y()
                         << "), path " << sound->score << " m";
      }
      goal_ = sound;
      goal_recoveries_ = 0;
      dwell_until_s_.reset();
    } else if (seeking && !dwell_until_s_) {
      // Keep the person, or drop them when they are no longer a goal (seen, visited).
      if (sound && same_target(*sound, *goal_)) {
        goal_ = sound;
      } else if (!sound) {
        goal_.reset();
      }
    }
  }

  if (!goal_ || goal_->kind == "frontier" || (goal_->kind == "sweep" && !frontiers.empty())) {
    if (goal_ && goal_->kind == "sweep") goal_.reset();  // a new frontier beats the sweep
    const auto best = ChooseFrontier(field, frontiers);
    bool keep = false;
    if (goal_) {
      // The current goal stays while it is still on a frontier and not clearly beaten.
      for (const Frontier& f : frontiers) {
        for (const auto& c : f.cells) {
          if ((map_.grid().CentreOf(c.x(), c.y()) - goal_->position_m).norm() < 0.25) {
            keep = true;
            break;
          }
        }
        if (keep) break;
      }
      if (keep) {
        const Eigen::Vector2i gc = map_.grid().CellOf(goal_->position_m);
        const int gi =
            map_.grid().Contains(gc.x(), gc.y()) ? map_.grid().Index(gc.x(), gc.y()) : -1;
        keep = field.Reached(gi) &&
               !(best && best->score < field.cost[gi] - options_.goals.size_weight -
                                           options_.goals.switch_margin_m);
      }
    }
    if (!keep) {
      goal_ = best;
      goal_recoveries_ = 0;
    }
  }

  if (!goal_ && options_.goals.when_explored == "sweep" && empty_plans_ >= 2) {
    goal_ = ChooseSweepGoal(now_s, field);
    if (goal_) {
      state_ = State::kSweeping;
      path_ = map_.PathTo(field, goal_->position_m);
      if (path_.empty()) GiveUpGoal(now_s);
      return;
    }
  }
  if (!goal_) {
    // Exploration ends only when several plans in a row find nothing (a new map can hide a
    // frontier for one plan while SLAM re-renders).
    if (++empty_plans_ < 3) {
      path_.clear();
      return;
    }
    if (!cleared_contacts_once_ && map_.ClearLoneContacts()) {
      // A bump marked once (not a glass pane) may be what closes the rest off: one more look
      // without those.
      cleared_contacts_once_ = true;
      empty_plans_ = 0;
      Replan(now_s);
      return;
    }
    if (!blacklist_.empty() && !cleared_blacklist_once_) {
      // Nothing else left: the given-up goals get one more chance.
      blacklist_.clear();
      cleared_blacklist_once_ = true;
      Replan(now_s);
      return;
    }
    state_ = options_.goals.return_home ? State::kReturning : State::kFinished;
    returning_explored_ = true;
    frontier_plans_returning_ = 0;
    path_.clear();
    if (state_ == State::kReturning) Replan(now_s);
    return;
  }
  if (goal_->kind == "sweep") {
    state_ = State::kSweeping;
    path_ = map_.PathTo(field, goal_->position_m);
    if (path_.empty()) GiveUpGoal(now_s);
    return;
  }
  empty_plans_ = 0;
  state_ = goal_->kind == "sound" ? State::kSeekingSound : State::kExploring;
  path_ = map_.PathTo(field, goal_->position_m);
  if (path_.empty()) GiveUpGoal(now_s);
}

Velocity ExploreController::Follow(const Scan& scan) {
  (void)scan;
  Velocity v;
  v.source = "planner";
  if (path_.empty()) return v;
  const Eigen::Vector2d robot = pose_->translation();
  // The path point nearest the robot, then the first one beyond the lookahead after it.
  size_t nearest = 0;
  double nearest_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < path_.size(); ++i) {
    const double d = (path_[i] - robot).norm();
    if (d < nearest_d) {
      nearest_d = d;
      nearest = i;
    }
  }
  size_t target_index = path_.size() - 1;
  for (size_t i = nearest; i < path_.size(); ++i) {
    if ((path_[i] - robot).norm() >= options_.follower.lookahead_m) {
      target_index = i;
      break;
    }
  }
  // The robot drives nearly straight at the target, so a target beyond a corner of the path
  // would have it cut the corner: the target comes back along the path until the straight line
  // to it keeps the clearance the path keeps (the planner's radius, or the clearance the robot
  // has now where that is less).
  if (map_.has_map()) {
    const Eigen::Vector2i here = map_.grid().CellOf(robot);
    const double needed =
        std::min(options_.planner.robot_radius_m, map_.Clearance(here.x(), here.y())) - 1e-6;
    while (target_index > nearest + 1 && map_.SegmentClearance(robot, path_[target_index]) < needed)
      --target_index;
  }
  const Eigen::Vector2d target = path_[target_index];
  const FollowerOptions& o = options_.follower;
  const Eigen::Vector2d local = pose_->inverse() * target;
  const double error = std::atan2(local.y(), local.x());
  v.angular_radps = std::clamp(o.heading_gain * error, -o.max_angular_radps, o.max_angular_radps);
  if (std::abs(error) > o.rotate_in_place_rad) return v;
  const double to_goal = (path_.back() - robot).norm();
  v.linear_mps = std::min(o.max_linear_mps * std::cos(error), 0.8 * to_goal + 0.05);
  return v;
}

Velocity ExploreController::Safe(Velocity desired, const Scan& scan) const {
  if (desired.linear_mps <= 0) return desired;
  const SafetyOptions& o = options_.safety;
  double clearance = ScanClearanceAhead(scan, o);
  // The map remembers what the camera can no longer see (nearer than its minimum range).
  const double half = 0.9 * options_.planner.robot_radius_m;
  const double step = 0.5 * map_.grid().resolution_m;
  const Eigen::Vector2d ahead(std::cos(pose_->yaw_rad()), std::sin(pose_->yaw_rad()));
  const Eigen::Vector2d side(-ahead.y(), ahead.x());
  for (double x = 0.3; x < std::min(clearance, o.slow_distance_m); x += step) {
    bool hit = false;
    for (double y = -half; y <= half + 1e-9; y += step)
      hit |= map_.Occupied(pose_->translation() + ahead * x + side * y);
    if (hit) {
      clearance = x;
      break;
    }
  }
  // ... and the safety layer's memory (odometry frame) what the map may have misplaced.
  for (const Eigen::Vector2d& q : local_points_) {
    if (q.x() > 0 && std::abs(q.y()) <= o.corridor_half_width_m)
      clearance = std::min(clearance, q.x());
  }
  if (ArcApproachesMemory(desired.linear_mps, desired.angular_radps)) {
    desired.linear_mps = 0;
    desired.source = "safety";
    return desired;
  }
  // The corridor ahead does not see a corner beside the robot that a turning arc cuts: follow
  // the commanded arc for sweep_horizon_s; if it brings the base nearer than footprint_radius_m
  // to an obstacle of the map (and nearer than it is now), no forward motion: the robot turns
  // on the spot first.
  if (map_.has_map() && o.sweep_horizon_s > 0) {
    const Eigen::Vector2i now_cell = map_.grid().CellOf(pose_->translation());
    const double clearance_now = map_.Clearance(now_cell.x(), now_cell.y());
    for (int k = 1; k <= 6; ++k) {
      const double t = o.sweep_horizon_s * k / 6;
      const double mean_yaw = pose_->yaw_rad() + 0.5 * desired.angular_radps * t;
      const Eigen::Vector2d p =
          pose_->translation() +
          desired.linear_mps * t * Eigen::Vector2d(std::cos(mean_yaw), std::sin(mean_yaw));
      const Eigen::Vector2i c = map_.grid().CellOf(p);
      const double clearance_then = map_.Clearance(c.x(), c.y());
      if (clearance_then < o.footprint_radius_m && clearance_then < clearance_now - 1e-3) {
        desired.linear_mps = 0;
        desired.source = "safety";
        return desired;
      }
    }
  }
  const double scale = std::clamp(
      (clearance - o.stop_distance_m) / (o.slow_distance_m - o.stop_distance_m), 0.0, 1.0);
  if (scale < 1.0) {
    const double limited = desired.linear_mps * scale;
    if (limited < desired.linear_mps - 1e-6) {
      desired.linear_mps = limited;
      if (scale == 0.0) desired.source = "safety";
    }
  }
  return desired;
}

void ExploreController::StartRecovery(double now_s, const Scan& scan, const std::string& why) {
  SARMAP_LOG(INFO) << "recovery at (" << pose_->translation().x() << ", "
                   << pose_->translation().y() << "): " << why;
  ++recoveries_;
  ++goal_recoveries_;
  if (goal_ && goal_recoveries_ > options_.recovery.attempts_per_goal) GiveUpGoal(now_s);
  resume_state_ = state_ == State::kRecovering ? resume_state_ : state_;
  state_ = State::kRecovering;
  BeginBackOff(now_s, scan);
  blocked_since_s_.reset();
  // Shut in recovery after recovery: the map around the robot's pose has no way out, so the
  // pose or the map is wrong. Turning and backing off on that map cannot help; driving where the
  // scan shows space (Escape) moves the robot to views from which SLAM can find it again.
  shut_in_recoveries_ = shut_in_ ? shut_in_recoveries_ + 1 : 0;
  // Recoveries repeating in one place (contacts and holds, each replan leading back into the
  // same spot) say the same: the map there is not where the robot is.
  const RecoveryOptions& o = options_.recovery;
  recent_recoveries_.emplace_back(now_s, pose_->translation());
  while (!recent_recoveries_.empty() &&
         now_s - recent_recoveries_.front().first > o.escape_window_s)
    recent_recoveries_.pop_front();
  const auto here = std::count_if(
      recent_recoveries_.begin(), recent_recoveries_.end(),
      [&](const auto& r) { return (r.second - pose_->translation()).norm() <= o.escape_radius_m; });
  const bool in_one_place = o.escape_window_s > 0 && here > o.escape_after;
  escape_until_s_.reset();
  if (o.escape_after > 0 && (shut_in_recoveries_ > o.escape_after || in_one_place)) {
    recovery_phase_ = 2;
    escape_until_s_ = now_s + o.escape_s;
    RestartContactWindow(now_s);
    shut_in_recoveries_ = 0;
    recent_recoveries_.clear();
    ++escapes_;
    SARMAP_LOG(WARN) << (in_one_place ? "recoveries repeating in one place"
                                      : "no plan out of the robot's place in the map")
                     << " after " << o.escape_after << " recoveries: escaping on the scan"
                     << (map_.Occupied(pose_->translation())
                             ? " alone (the pose is inside an obstacle)"
                             : " and the map")
                     << " for " << options_.recovery.escape_s << " s (escape " << escapes_ << ")";
  }
}

Velocity ExploreController::Recover(double now_s, const Scan& scan) {
  const RecoveryOptions& o = options_.recovery;
  Velocity v;
  v.source = "recovery";
  if (recovery_phase_ == 2) {
    if (escape_until_s_ && now_s < *escape_until_s_) return Escape(now_s, scan);
    return EndRecovery(now_s);
  }
  if (recovery_phase_ == 0) {
    // Back off while the map behind the robot is free of obstacles.
    const Eigen::Vector2d back(-std::cos(pose_->yaw_rad()), -std::sin(pose_->yaw_rad()));
    const Eigen::Vector2d side(-back.y(), back.x());
    bool clear = true;
    for (double x = 0.25; x <= 0.5; x += 0.05) {
      for (double y = -0.2; y <= 0.2 + 1e-9; y += 0.1)
        clear &= !map_.Occupied(pose_->translation() + back * x + side * y);
    }
    clear &= !ArcApproachesMemory(-o.backoff_speed_mps, 0.0);
    const bool done =
        (pose_->translation() - recovery_xy0_).norm() >= o.backoff_m ||
        now_s - recovery_phase_start_s_ > 2.0 * o.backoff_m / o.backoff_speed_mps + 1.0;
    if (clear && !done && o.backoff_m > 0) {
      v.linear_mps = -o.backoff_speed_mps;
      return v;
    }
    recovery_phase_ = 1;
    recovery_phase_start_s_ = now_s;
    recovery_yaw0_ = pose_->yaw_rad();
  }
  const double turned = std::abs(common::WrapAngle(pose_->yaw_rad() - recovery_yaw0_));
  if (turned < o.turn_rad &&
      now_s - recovery_phase_start_s_ < 2.0 * o.turn_rad / o.turn_speed_radps + 1.0) {
    v.angular_radps = recovery_turn_sign_ * o.turn_speed_radps;
    return v;
  }
  if (escape_until_s_ && now_s < *escape_until_s_) {
    // Backed off and turned after a contact while escaping: the escape goes on.
    recovery_phase_ = 2;
    RestartContactWindow(now_s);
    return Escape(now_s, scan);
  }
  return EndRecovery(now_s);
}

void ExploreController::BeginBackOff(double now_s, const Scan& scan) {
  recovery_phase_ = 0;
  recovery_phase_start_s_ = now_s;
  recovery_xy0_ = pose_->translation();
  recovery_yaw0_ = pose_->yaw_rad();
  const ScanMetrics m = AnalyseScan(scan, options_.reactive);
  recovery_turn_sign_ = m.mean_left_m >= m.mean_right_m ? 1.0 : -1.0;
}

Velocity ExploreController::Escape(double now_s, const Scan& scan) {
  // Something the scan does not show (low debris nearer than where the camera's view meets the
  // floor, a body beside the base) stops the robot as it does when following a plan: marked,
  // backed off from, turned away from; the escape then goes on.
  if (ContactInWindow(now_s)) {
    const bool marked = map_.AddContact(*pose_);
    ++recoveries_;
    SARMAP_LOG(INFO) << "contact while escaping at (" << pose_->translation().x() << ", "
                     << pose_->translation().y() << ")" << (marked ? ", marked" : "");
    BeginBackOff(now_s, scan);
    return Recover(now_s, scan);
  }
  Velocity v = reactive_.Step(scan);
  // A pose inside one of the map's obstacles is wrong, and so is the map around it: the scan
  // alone drives. Otherwise the map keeps what the scan cannot see now (low debris close by,
  // contacts, what is beside the base), and the robot moves only where both allow: where the
  // map holds it, it turns on the spot (safe for a round base) until they agree.
  if (map_.has_map() && !map_.Occupied(pose_->translation())) {
    const Velocity safe = Safe(v, scan);
    if (v.linear_mps > 0.02 && safe.linear_mps < 0.02) {
      v.linear_mps = 0;
      const double sign =
          v.angular_radps != 0 ? (v.angular_radps > 0 ? 1.0 : -1.0) : recovery_turn_sign_;
      v.angular_radps = sign * options_.recovery.turn_speed_radps;
    } else {
      v = safe;
    }
  }
  v.source = "escape";
  return v;
}

void ExploreController::RestartContactWindow(double now_s) {
  contact_since_s_ = now_s;
  contact_xy_ = pose_->translation();
  commanded_m_ = 0;
}

bool ExploreController::ContactInWindow(double now_s) {
  // Told to go forward for a while, hardly moved: glass, or something below the scan's band.
  commanded_m_ += std::max(0.0, last_linear_mps_) * std::max(0.0, now_s - last_scan_s_);
  if (now_s - contact_since_s_ < options_.recovery.contact_window_s) return false;
  const double moved = (pose_->translation() - contact_xy_).norm();
  const bool contact = commanded_m_ > 0.1 && moved < options_.recovery.contact_ratio * commanded_m_;
  RestartContactWindow(now_s);
  return contact;
}

Velocity ExploreController::EndRecovery(double now_s) {
  // Replan from here.
  Velocity v;
  v.source = "recovery";
  state_ = resume_state_;
  escape_until_s_.reset();
  RestartContactWindow(now_s);
  progress_xy_ = pose_->translation();
  progress_yaw_ = pose_->yaw_rad();
  progress_s_ = now_s;
  last_plan_s_ = -1e9;
  return v;
}

Velocity ExploreController::WaitForPose(double now_s) {
  if (!pose_wait_since_s_) {
    pose_wait_since_s_ = now_s;
    pose_wait_warned_ = false;
    ++pose_waits_;
  }
  if (!pose_wait_warned_ && now_s - *pose_wait_since_s_ > 5.0) {
    pose_wait_warned_ = true;
    SARMAP_LOG(WARN) << "no POSE within " << options_.safety.max_pose_age_s
                     << " s of the SCAN for 5 s: standing still until SLAM catches up (is SLAM "
                        "running, and are POSE and SCAN stamped on one clock?)";
  }
  Velocity v;
  v.source = "pose_wait";
  return v;
}

void ExploreController::ResumeAfterPoseWait(double now_s) {
  const double waited_s = now_s - *pose_wait_since_s_;
  pose_wait_since_s_.reset();
  if (waited_s > 1.0) {
    SARMAP_LOG(INFO) << "stood " << waited_s << " s waiting for POSE (" << pose_waits_
                     << " waits so far)";
  }
  progress_s_ += waited_s;
  RestartContactWindow(now_s);
  if (blocked_since_s_) *blocked_since_s_ += waited_s;
  recovery_phase_start_s_ += waited_s;
  if (escape_until_s_) *escape_until_s_ += waited_s;
  if (dwell_until_s_) *dwell_until_s_ += waited_s;
}

Velocity ExploreController::Drive(double now_s, const Scan& scan) {
  const bool was_looking = looking_;
  looking_ = false;
  Velocity stop;
  stop.source = "stop";
  switch (state_) {
    case State::kHome:
    case State::kFinished:
      return stop;
    case State::kLookAround: {
      const bool done =
          look_turned_rad_ >= 2 * M_PI || (start_s_ && now_s - *start_s_ > 4 * M_PI / 0.5);
      if (!done) {
        Velocity v;
        v.source = "look";
        v.angular_radps = 0.5;
        return v;
      }
      state_ = State::kExploring;
      progress_s_ = now_s;
      last_plan_s_ = -1e9;
      break;
    }
    case State::kRecovering:
      return Recover(now_s, scan);
    default:
      break;
  }
  const double since_plan_s = now_s - last_plan_s_;
  if (since_plan_s >= options_.goals.replan_period_s ||
      (goal_ && path_.empty() && since_plan_s >= 0.25)) {
    Replan(now_s);
  }
  if (state_ == State::kHome || state_ == State::kFinished) return stop;
  if (!goal_ || path_.empty()) {
    // No path now (e.g. the robot stands in an inflated cell): the stuck detector decides.
    stop.source = "planner";
    if (now_s - progress_s_ > options_.recovery.stuck_timeout_s)
      StartRecovery(now_s, scan, "no plan and no progress");
    return stop;
  }
  const Eigen::Vector2d robot = pose_->translation();
  const bool reached = (robot - goal_->position_m).norm() < options_.goals.goal_reached_m;
  if (reached || dwell_until_s_) {
    if (goal_->kind == "home") {
      state_ = State::kHome;
      goal_.reset();
      path_.clear();
      return stop;
    }
    // Face what the goal was for (the frontier's unknown, the heard person), then move on.
    if (goal_->face_m) {
      const Eigen::Vector2d local = pose_->inverse() * *goal_->face_m;
      const double error = std::atan2(local.y(), local.x());
      if (std::abs(error) > 0.25 && !dwell_until_s_) {
        Velocity v;
        v.source = "planner";
        v.angular_radps =
            std::clamp(options_.follower.heading_gain * error, -options_.follower.max_angular_radps,
                       options_.follower.max_angular_radps);
        progress_s_ = now_s;
        return v;
      }
    }
    if (goal_->kind == "sound") {
      if (!dwell_until_s_)
        dwell_until_s_ = now_s + (goal_->voice ? options_.sound.listen_s : options_.sound.dwell_s);
      if (now_s < *dwell_until_s_) {
        progress_s_ = now_s;
        Velocity v;
        v.source = "planner";
        return v;
      }
      visited_sound_.push_back(*goal_->face_m);
    } else if (goal_->kind == "frontier") {
      // A frontier still there after looking at it from its edge is one the camera cannot
      // resolve from anywhere it can reach (under furniture, behind a screen): not again.
      blacklist_.push_back({goal_->position_m, std::numeric_limits<double>::infinity()});
    }
    goal_.reset();
    path_.clear();
    dwell_until_s_.reset();
    goal_recoveries_ = 0;
    Replan(now_s);
    if (!goal_ || path_.empty()) return stop;
  }
  // Contact: mark it, and recover from there.
  if (ContactInWindow(now_s)) {
    const bool marked = map_.AddContact(*pose_);
    StartRecovery(now_s, scan, marked ? "contact, marked" : "contact with an obstacle the map has");
    return Recover(now_s, scan);
  }
  Velocity desired = Follow(scan);
  // Space the base is about to sweep that the sensor has never seen (beside a doorway, inside
  // a turn): turn on the spot to look at it first; the next plan goes around what is there.
  if (const std::optional<Eigen::Vector2d> unseen = UnseenOnArc(desired, scan)) {
    const Eigen::Vector2d local = pose_->inverse() * *unseen;
    const double error = std::atan2(local.y(), local.x());
    desired.linear_mps = 0;
    desired.angular_radps =
        std::clamp(options_.follower.heading_gain * error, -options_.follower.max_angular_radps,
                   options_.follower.max_angular_radps);
    desired.source = "look";
    if (!was_looking) ++looks_;
    looking_ = true;
  }
  const Velocity safe = Safe(desired, scan);
  // Progress: moved or turned enough since the last mark.
  if ((robot - progress_xy_).norm() > options_.recovery.progress_m ||
      std::abs(common::WrapAngle(pose_->yaw_rad() - progress_yaw_)) >
          options_.recovery.progress_rad) {
    progress_xy_ = robot;
    progress_yaw_ = pose_->yaw_rad();
    progress_s_ = now_s;
  }
  const bool held = desired.linear_mps > 0.02 && safe.linear_mps < 0.02;
  if (held) {
    if (!blocked_since_s_) blocked_since_s_ = now_s;
    // The scan sees what the map does not yet have: plan again around it.
    if (now_s - last_plan_s_ > 0.3) last_plan_s_ = -1e9;
  } else {
    blocked_since_s_.reset();
  }
  if (now_s - progress_s_ > options_.recovery.stuck_timeout_s ||
      (blocked_since_s_ && now_s - *blocked_since_s_ > options_.recovery.blocked_timeout_s)) {
    StartRecovery(now_s, scan,
                  now_s - progress_s_ > options_.recovery.stuck_timeout_s
                      ? "no progress"
                      : "held by the safety layer");
    return Recover(now_s, scan);
  }
  return safe;
}

Velocity ExploreController::OnScan(double now_s, const Scan& scan) {
  status_.driven_by.clear();
  Velocity out;
  // The operator first: an override lasts while messages keep arriving (measured on this
  // process's clock), with clamped speeds; an emergency stop holds until released, through any
  // override the operator drives in the meantime.
  if (teleop_ && teleop_->override_active && !teleop_->emergency_stop &&
      now_s - teleop_->receive_time_s <= options_.teleop_timeout_s &&
      now_s >= teleop_->receive_time_s - 1e-3) {
    out.linear_mps = std::clamp(teleop_->linear_mps, -options_.teleop_max_linear_mps,
                                options_.teleop_max_linear_mps);
    out.angular_radps = std::clamp(teleop_->angular_radps, -options_.teleop_max_angular_radps,
                                   options_.teleop_max_angular_radps);
    out.source = "teleop";
    status_.state = "override";
    status_.driven_by = out.source;
    return out;
  }
  if (emergency_stop_) {
    out.source = "stop";
    status_.state = "override";
    status_.driven_by = out.source;
    return out;
  }
  if (!start_s_) {
    start_s_ = now_s;
    progress_s_ = now_s;
  }
  status_.elapsed_s = now_s - *start_s_;
  if (options_.mode == "reactive") {
    out = reactive_.Step(scan);
    status_.state = "exploring";
  } else if (!map_.has_map() || !pose_) {
    // Until SLAM has a map and a pose: turn on the spot (safe for a round base) so that it has
    // something to map.
    out.source = "look";
    out.angular_radps = 0.5;
    status_.state = StateName(state_);
  } else if (options_.safety.max_pose_age_s > 0 &&
             scan.stamp_s - pose_stamp_s_ > options_.safety.max_pose_age_s) {
    // Where the robot is now is not known well enough to place the scan or to drive.
    out = WaitForPose(now_s);
    last_linear_mps_ = 0;
    status_.state = StateName(state_);
  } else {
    if (pose_wait_since_s_) ResumeAfterPoseWait(now_s);
    map_.IntegrateScan(*pose_, scan);
    if (options_.safety.memory_s > 0) {
      // Odometry when it comes, else SLAM's pose; a change of frame starts the memory again.
      std::optional<common::Rigid2d> local_from_base = OdometryAt(scan.stamp_s);
      const bool is_odometry = local_from_base.has_value();
      if (!is_odometry) local_from_base = pose_;
      if (is_odometry != local_frame_is_odometry_) local_obstacles_.Clear();
      local_frame_is_odometry_ = is_odometry;
      local_obstacles_.Add(scan.stamp_s, *local_from_base, scan);
      local_points_ = local_obstacles_.InBase(*local_from_base);
    }
    out = Drive(now_s, scan);
    last_linear_mps_ = out.linear_mps;
    status_.state = StateName(state_);
  }
  status_.driven_by = out.source;
  status_.goal_m.reset();
  status_.goal_kind.clear();
  if (goal_) {
    status_.goal_m = goal_->position_m;
    status_.goal_kind = goal_->kind;
  }
  status_.path = path_;
  status_.frontiers = frontier_count_;
  status_.blacklisted = static_cast<int>(blacklist_.size());
  status_.recoveries = recoveries_;
  status_.contacts = map_.contacts();
  status_.looks = looks_;
  if (status_.state != logged_state_) {
    // Each change of the mission's state, once: the live log tells why a mission ended.
    std::ostringstream line;
    line << "t+" << static_cast<int>(status_.elapsed_s) << " s: " << logged_state_ << " -> "
         << status_.state << " (" << frontier_count_ << " frontiers, " << blacklist_.size()
         << " goals given up";
    if (goal_)
      line << ", goal " << goal_->kind << " at (" << goal_->position_m.x() << ", "
           << goal_->position_m.y() << ")";
    line << ")";
    SARMAP_LOG(INFO) << line.str();
    logged_state_ = status_.state;
  }
  last_scan_s_ = now_s;
  status_.stuck_s = state_ == State::kHome || state_ == State::kFinished
                        ? 0.0
                        : std::max(0.0, now_s - progress_s_);
  return out;
}

}  // namespace explore
}  // namespace sarmap
