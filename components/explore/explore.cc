#include "explore/explore.h"

#include <cmath>
#include <limits>
#include <queue>

namespace sarmap {
namespace explore {

ScanMetrics AnalyseScan(const Scan& scan, const ReactiveOptions& options) {
  ScanMetrics m;
  m.min_valid_m = std::numeric_limits<double>::infinity();
  double sum_left = 0, sum_right = 0;
  int n_left = 0, n_right = 0, unknown_left = 0, unknown_right = 0;
  const double upper = scan.range_max_m - options.max_range_margin_m;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double angle = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const bool left = angle > 0;
    const double r = scan.ranges_m[i];
    const bool valid = std::isfinite(r) && r >= scan.range_min_m && r <= upper;
    (left ? n_left : n_right)++;
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
  const bool in_danger = m.min_valid_m < options_.danger_distance_m || m.unknown_rate >= options_.unknown_rate_limit;
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

Eigen::Vector2i Grid::CellOf(const Eigen::Vector2d& p) const {
  return Eigen::Vector2i(static_cast<int>(std::floor((p.x() - origin_x_m) / resolution_m)),
                         static_cast<int>(std::floor((p.y() - origin_y_m) / resolution_m)));
}

Eigen::Vector2d Grid::CentreOf(int x, int y) const {
  return Eigen::Vector2d(origin_x_m + (x + 0.5) * resolution_m, origin_y_m + (y + 0.5) * resolution_m);
}

void FrontierExplorer::SetMap(Grid grid) {
  grid_ = std::move(grid);
  blocked_.assign(grid_.cells.size(), 0);
  const int r = static_cast<int>(std::ceil(options_.robot_radius_m / grid_.resolution_m));
  for (int y = 0; y < grid_.height; ++y) {
    for (int x = 0; x < grid_.width; ++x) {
      if (grid_.at(x, y) < options_.occupied_threshold) continue;
      for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
          if (dx * dx + dy * dy > r * r || !grid_.Contains(x + dx, y + dy)) continue;
          blocked_[static_cast<size_t>(y + dy) * grid_.width + x + dx] = 1;
        }
      }
    }
  }
}

bool FrontierExplorer::Traversable(int x, int y) const {
  if (!grid_.Contains(x, y)) return false;
  const int8_t v = grid_.at(x, y);
  return v >= 0 && v < options_.free_threshold && !blocked_[static_cast<size_t>(y) * grid_.width + x];
}

void FrontierExplorer::Plan(const Eigen::Vector2d& robot_xy, std::vector<double>* cost,
                            std::vector<int>* parent) const {
  const size_t n = grid_.cells.size();
  cost->assign(n, std::numeric_limits<double>::infinity());
  parent->assign(n, -1);
  const Eigen::Vector2i start = grid_.CellOf(robot_xy);
  if (!grid_.Contains(start.x(), start.y())) return;
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  const int s = start.y() * grid_.width + start.x();
  (*cost)[s] = 0;
  open.push({0.0, s});
  while (!open.empty()) {
    const auto [c, i] = open.top();
    open.pop();
    if (c > (*cost)[i]) continue;
    const int x = i % grid_.width, y = i / grid_.width;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const int nx = x + dx, ny = y + dy;
        // The start cell may be inside an inflated obstacle (robot close to a wall): leave it.
        if (!Traversable(nx, ny)) continue;
        const int j = ny * grid_.width + nx;
        const double step = (dx && dy ? M_SQRT2 : 1.0) * grid_.resolution_m;
        if (c + step < (*cost)[j]) {
          (*cost)[j] = c + step;
          (*parent)[j] = i;
          open.push({c + step, j});
        }
      }
    }
  }
}

std::vector<Frontier> FrontierExplorer::Frontiers(const Eigen::Vector2d& robot_xy) const {
  std::vector<Frontier> out;
  if (grid_.width == 0) return out;
  std::vector<double> cost;
  std::vector<int> parent;
  Plan(robot_xy, &cost, &parent);
  const auto is_frontier = [&](int x, int y) {
    if (!Traversable(x, y)) return false;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (grid_.Contains(x + dx, y + dy) && grid_.at(x + dx, y + dy) < 0) return true;
    return false;
  };
  std::vector<uint8_t> seen(grid_.cells.size(), 0);
  for (int y = 0; y < grid_.height; ++y) {
    for (int x = 0; x < grid_.width; ++x) {
      const size_t i = static_cast<size_t>(y) * grid_.width + x;
      if (seen[i] || !is_frontier(x, y)) continue;
      Frontier f;
      std::queue<Eigen::Vector2i> todo;
      todo.push({x, y});
      seen[i] = 1;
      double best = std::numeric_limits<double>::infinity();
      while (!todo.empty()) {
        const Eigen::Vector2i c = todo.front();
        todo.pop();
        f.cells.push_back(c);
        const double cc = cost[static_cast<size_t>(c.y()) * grid_.width + c.x()];
        if (cc < best) {
          best = cc;
          f.goal_m = grid_.CentreOf(c.x(), c.y());
        }
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = c.x() + dx, ny = c.y() + dy;
            if (!grid_.Contains(nx, ny)) continue;
            const size_t j = static_cast<size_t>(ny) * grid_.width + nx;
            if (!seen[j] && is_frontier(nx, ny)) {
              seen[j] = 1;
              todo.push({nx, ny});
            }
          }
        }
      }
      if (static_cast<int>(f.cells.size()) < options_.min_frontier_cells || !std::isfinite(best)) continue;
      bool blacklisted = false;
      for (const auto& b : blacklist_) blacklisted |= (b - f.goal_m).norm() < options_.blacklist_radius_m;
      if (blacklisted) continue;
      f.path_cost_m = best;
      out.push_back(std::move(f));
    }
  }
  std::sort(out.begin(), out.end(), [&](const Frontier& a, const Frontier& b) {
    return a.path_cost_m - options_.size_weight_m * a.cells.size() <
           b.path_cost_m - options_.size_weight_m * b.cells.size();
  });
  return out;
}

void FrontierExplorer::AbandonGoal() {
  if (goal_) blacklist_.push_back(*goal_);
  goal_.reset();
  path_.clear();
}

std::optional<Velocity> FrontierExplorer::Step(const common::Rigid2d& map_from_base) {
  const Eigen::Vector2d robot = map_from_base.translation();
  if (goal_ && (robot - *goal_).norm() < options_.goal_reached_m) goal_.reset();
  // Replan every step: the map grows as the robot moves, and planning is cheap at 5 cm.
  const auto frontiers = Frontiers(robot);
  if (frontiers.empty()) {
    goal_.reset();
    path_.clear();
    return std::nullopt;
  }
  goal_ = frontiers.front().goal_m;
  std::vector<double> cost;
  std::vector<int> parent;
  Plan(robot, &cost, &parent);
  path_.clear();
  const Eigen::Vector2i g = grid_.CellOf(*goal_);
  for (int i = g.y() * grid_.width + g.x(); i >= 0; i = parent[i]) {
    path_.push_back(grid_.CentreOf(i % grid_.width, i / grid_.width));
  }
  std::reverse(path_.begin(), path_.end());
  // Pure pursuit to the first path point beyond the lookahead.
  Eigen::Vector2d target = path_.back();
  for (const auto& p : path_) {
    if ((p - robot).norm() >= options_.lookahead_m) {
      target = p;
      break;
    }
  }
  const Eigen::Vector2d local = map_from_base.inverse() * target;
  const double heading_error = std::atan2(local.y(), local.x());
  Velocity v;
  v.source = "frontier";
  v.angular_radps = std::clamp(2.0 * heading_error, -options_.max_angular_radps, options_.max_angular_radps);
  // Turn on the spot when facing away; slow down in turns.
  v.linear_mps = std::abs(heading_error) > 0.8 ? 0.0 : options_.max_linear_mps * std::cos(heading_error);
  return v;
}

Velocity ExploreController::OnScan(common::Utime utime, const Scan& scan) {
  if (teleop_ && common::UtimeToSeconds(utime - teleop_->utime) <= options_.teleop_timeout_s) {
    Velocity v;
    if (teleop_->emergency_stop) {
      v.source = "stop";
      return v;
    }
    if (teleop_->override_active) {
      v.linear_mps = teleop_->linear_mps;
      v.angular_radps = teleop_->angular_radps;
      v.source = "teleop";
      return v;
    }
  } else if (teleop_ && teleop_->emergency_stop) {
    Velocity v;  // an emergency stop holds until the operator releases it
    v.source = "stop";
    return v;
  }
  bool danger = false;
  const Velocity reactive = reactive_.Step(scan, &danger);
  if (options_.mode != "frontier" || !frontier_.has_map() || !pose_) return reactive;
  if (danger) {
    // The safety layer steers; if it keeps blocking the same goal, give that goal up.
    if (++blocked_scans_ > 60) {
      frontier_.AbandonGoal();
      blocked_scans_ = 0;
    }
    return reactive;
  }
  blocked_scans_ = 0;
  auto v = frontier_.Step(*pose_);
  if (!v) {
    finished_ = true;
    Velocity stop;
    stop.source = "stop";
    return stop;
  }
  return *v;
}

}  // namespace explore
}  // namespace sarmap
