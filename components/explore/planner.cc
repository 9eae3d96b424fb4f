#include "explore/planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace sarmap {
namespace explore {

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
// How far past its minimum range a beam without information counts as looked along.
constexpr double kNearFieldM = 1.0;
}  // namespace

Eigen::Vector2i Grid::CellOf(const Eigen::Vector2d& p) const {
  return Eigen::Vector2i(static_cast<int>(std::floor((p.x() - origin_x_m) / resolution_m)),
                         static_cast<int>(std::floor((p.y() - origin_y_m) / resolution_m)));
}

Eigen::Vector2d Grid::CentreOf(int x, int y) const {
  return Eigen::Vector2d(origin_x_m + (x + 0.5) * resolution_m,
                         origin_y_m + (y + 0.5) * resolution_m);
}

void ExploreMap::SetMap(const Grid& map) {
  last_map_ = map;
  const Grid previous = std::move(grid_);
  const std::vector<uint8_t> previous_crossed = std::move(crossed_);
  const std::vector<uint8_t> previous_hit = std::move(hit_);
  const std::vector<float> previous_visible_from = std::move(hit_visible_from_m_);
  const std::vector<uint8_t> previous_viewed = std::move(viewed_);
  const int pad = static_cast<int>(std::ceil(options_.pad_m / map.resolution_m));
  grid_.resolution_m = map.resolution_m;
  grid_.width = map.width + 2 * pad;
  grid_.height = map.height + 2 * pad;
  grid_.origin_x_m = map.origin_x_m - pad * map.resolution_m;
  grid_.origin_y_m = map.origin_y_m - pad * map.resolution_m;
  grid_.cells.assign(static_cast<size_t>(grid_.width) * grid_.height, -1);
  for (int y = 0; y < map.height; ++y) {
    std::copy(map.cells.begin() + static_cast<size_t>(y) * map.width,
              map.cells.begin() + static_cast<size_t>(y + 1) * map.width,
              grid_.cells.begin() + static_cast<size_t>(y + pad) * grid_.width + pad);
  }
  // Calls f(index in the previous grid, cell in this one) for every cell of the previous grid
  // marked in `mask` that this grid contains.
  const auto carry_over = [&](const std::vector<uint8_t>& mask, auto&& f) {
    for (int y = 0; y < previous.height; ++y) {
      for (int x = 0; x < previous.width; ++x) {
        const int i = previous.Index(x, y);
        if (!mask[i]) continue;
        const Eigen::Vector2i c = grid_.CellOf(previous.CentreOf(x, y));
        if (grid_.Contains(c.x(), c.y())) f(i, c);
      }
    }
  };
  // Seen: what MAP knows, and what the explorer's own view or body covered before.
  viewed_.assign(grid_.cells.size(), 0);
  for (size_t i = 0; i < grid_.cells.size(); ++i) viewed_[i] = grid_.cells[i] >= 0;
  carry_over(previous_viewed,
             [&](int, const Eigen::Vector2i& c) { viewed_[grid_.Index(c.x(), c.y())] = 1; });
  // The explorer's own returns since they were last crossed stay obstacles unless the new map
  // calls the cell free: SLAM renders a low object seen from afar in a few scans as uncertain,
  // and the camera cannot see it again once the robot is close. A return the sensor loses from
  // view close by (visible_from beyond the sensor's minimum range) stays even then: SLAM's rays
  // from close by passed over it. MAP's own obstacles are not carried over: SLAM moves its
  // walls when it re-optimises, and old copies left in cells it has no verdict on (a doorway
  // seen edge-on) would close the door.
  hit_.assign(grid_.cells.size(), 0);
  hit_visible_from_m_.assign(grid_.cells.size(), 0.0f);
  carry_over(previous_hit, [&](int i, const Eigen::Vector2i& c) {
    int8_t& v = grid_.at(c.x(), c.y());
    const bool lost_close_by = previous_visible_from[i] > scan_range_min_m_ + 1e-3;
    if ((v >= 0 && v < options_.free_threshold && !lost_close_by) ||
        v >= options_.occupied_threshold) {
      return;
    }
    v = 100;
    hit_[grid_.Index(c.x(), c.y())] = 1;
    hit_visible_from_m_[grid_.Index(c.x(), c.y())] = previous_visible_from[i];
  });
  // Cells the explorer's rays crossed stay free where MAP has no verdict; MAP's obstacles win.
  crossed_.assign(grid_.cells.size(), 0);
  carry_over(previous_crossed, [&](int, const Eigen::Vector2i& c) {
    int8_t& v = grid_.at(c.x(), c.y());
    if (v >= options_.occupied_threshold) return;
    v = 0;
    crossed_[grid_.Index(c.x(), c.y())] = 1;
  });
  for (const auto& p : trail_) Stamp(p);
  for (const auto& c : contacts_) StampContact(c);
  for (auto& line : lines_) StampLine(line);
}

bool ExploreMap::AddContact(const common::Rigid2d& map_from_base) {
  // A contact is a surface across the robot's front. Two contacts whose points are between
  // the robot's width and glass_join_m apart, each made heading into the line through them
  // (within 60 deg of its normal) from the same side, with no MAP obstacle between them (the
  // camera sees through), are one invisible surface, a glass pane: the segment between them is
  // an obstacle too, extended along the line over the seen-through cells until it meets an
  // obstacle the map has (a pier, a wall) or glass_extend_m.
  const double ahead = options_.robot_radius_m + grid_.resolution_m;
  const Eigen::Vector2d point = map_from_base * Eigen::Vector2d(ahead, 0.0);
  const Eigen::Vector2d heading(std::cos(map_from_base.yaw_rad()),
                                std::sin(map_from_base.yaw_rad()));
  // Something the map already has at the robot's front (a door jamb brushed in passing) needs
  // no mark; a mark beside it would narrow the doorway.
  if (has_map()) {
    const double reach = options_.robot_radius_m + 0.1;
    const int r = static_cast<int>(std::ceil(reach / grid_.resolution_m));
    const Eigen::Vector2i c = grid_.CellOf(map_from_base.translation());
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        if (!grid_.Contains(c.x() + dx, c.y() + dy)) continue;
        const Eigen::Vector2d local =
            map_from_base.inverse() * grid_.CentreOf(c.x() + dx, c.y() + dy);
        if (local.x() <= 0 || local.norm() > reach) continue;
        const int i = grid_.Index(c.x() + dx, c.y() + dy);
        if (grid_.cells[i] >= options_.occupied_threshold && !hit_[i]) return false;
      }
    }
  }
  bool joined = false;
  for (const common::Rigid2d& c : contacts_) {
    const Eigen::Vector2d other = c * Eigen::Vector2d(ahead, 0.0);
    const Eigen::Vector2d other_heading(std::cos(c.yaw_rad()), std::sin(c.yaw_rad()));
    const double apart = (point - other).norm();
    if (apart < 2 * options_.robot_radius_m || apart > options_.glass_join_m) continue;
    const Eigen::Vector2d along = (point - other) / apart;
    const Eigen::Vector2d normal(-along.y(), along.x());
    const double into = std::cos(60.0 * M_PI / 180.0);
    if (std::abs(heading.dot(normal)) < into || std::abs(other_heading.dot(normal)) < into)
      continue;
    if (heading.dot(normal) * other_heading.dot(normal) < 0) continue;  // from opposite sides
    if (has_map() && !NoObstacleBetween(other + along * options_.robot_radius_m,
                                        point - along * options_.robot_radius_m)) {
      continue;
    }
    lines_.push_back({other, point});
    in_line_[&c - contacts_.data()] = true;
    joined = true;
    if (has_map()) StampLine(lines_.back());
  }
  contacts_.push_back(map_from_base);
  in_line_.push_back(joined);
  if (has_map()) StampContact(map_from_base);
  return true;
}

bool ExploreMap::ClearLoneContacts() {
  std::vector<common::Rigid2d> kept;
  for (size_t i = 0; i < contacts_.size(); ++i) {
    if (in_line_[i]) kept.push_back(contacts_[i]);
  }
  if (kept.size() == contacts_.size()) return false;
  contacts_ = kept;
  in_line_.assign(contacts_.size(), true);
  const Grid map = last_map_;
  SetMap(map);
  return true;
}

bool ExploreMap::NoObstacleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  // On MAP as received (the contacts' own marks do not count).
  const double length = (b - a).norm();
  const int steps = static_cast<int>(length / (0.5 * grid_.resolution_m)) + 1;
  for (int k = 0; k <= steps; ++k) {
    const Eigen::Vector2i c = last_map_.CellOf(a + (b - a) * (static_cast<double>(k) / steps));
    if (last_map_.Contains(c.x(), c.y()) &&
        last_map_.at(c.x(), c.y()) >= options_.occupied_threshold)
      return false;
  }
  return true;
}

bool ExploreMap::ClearContactsBounding(const CostField& field) {
  const int r = static_cast<int>(
      std::ceil((options_.robot_radius_m + 2 * grid_.resolution_m) / grid_.resolution_m));
  const auto bounds = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2i c = grid_.CellOf(p);
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        if (grid_.Contains(c.x() + dx, c.y() + dy) &&
            field.Reached(grid_.Index(c.x() + dx, c.y() + dy)))
          return true;
      }
    }
    return false;
  };
  const size_t before = contacts_.size() + lines_.size();
  const double ahead = options_.robot_radius_m + grid_.resolution_m;
  std::vector<common::Rigid2d> kept;
  std::vector<bool> kept_in_line;
  for (size_t i = 0; i < contacts_.size(); ++i) {
    if (bounds(contacts_[i] * Eigen::Vector2d(ahead, 0.0))) continue;
    kept.push_back(contacts_[i]);
    kept_in_line.push_back(in_line_[i]);
  }
  contacts_ = std::move(kept);
  in_line_ = std::move(kept_in_line);
  lines_.erase(std::remove_if(
                   lines_.begin(), lines_.end(),
                   [&](const GlassLine& line) {
                     const double length = (line.b_m - line.a_m).norm();
                     for (double t = 0; t <= length; t += grid_.resolution_m) {
                       if (bounds(line.a_m + (line.b_m - line.a_m) * (t / std::max(length, 1e-9))))
                         return true;
                     }
                     return false;
                   }),
               lines_.end());
  if (contacts_.size() + lines_.size() == before) return false;
  const Grid map = last_map_;
  SetMap(map);
  return true;
}

void ExploreMap::StampLine(GlassLine& line) {
  const double res = grid_.resolution_m;
  const Eigen::Vector2d along = (line.b_m - line.a_m).normalized();
  // Extend once, on the map the line was found on; later maps stamp the same extent.
  if (!line.extended) {
    line.extended = true;
    for (int side = -1; side <= 1; side += 2) {
      Eigen::Vector2d& end = side < 0 ? line.a_m : line.b_m;
      const Eigen::Vector2d start = end;
      // From beyond the contact's own stamp (half the robot's width).
      for (double t = options_.robot_radius_m + res; t <= options_.glass_extend_m; t += 0.5 * res) {
        const Eigen::Vector2d p = start + side * along * t;
        const Eigen::Vector2i c = grid_.CellOf(p);
        if (!grid_.Contains(c.x(), c.y())) break;
        const int8_t v = grid_.at(c.x(), c.y());
        if (v >= options_.occupied_threshold) break;  // met the wall or pier it spans to
        if (v < 0) break;                             // nothing seen beyond: no evidence
        end = p;
      }
    }
  }
  const double length = (line.b_m - line.a_m).norm();
  for (double t = 0; t <= length + 1e-9; t += 0.5 * res) {
    const Eigen::Vector2i c = grid_.CellOf(line.a_m + along * t);
    if (grid_.Contains(c.x(), c.y())) grid_.at(c.x(), c.y()) = 100;
  }
}

void ExploreMap::StampContact(const common::Rigid2d& map_from_base) {
  // Just beyond the front of the robot, over its width (what it pushed against).
  const double ahead = options_.robot_radius_m + grid_.resolution_m;
  const double half = options_.robot_radius_m;
  for (double y = -half; y <= half + 1e-9; y += 0.5 * grid_.resolution_m) {
    const Eigen::Vector2i c = grid_.CellOf(map_from_base * Eigen::Vector2d(ahead, y));
    if (grid_.Contains(c.x(), c.y())) grid_.at(c.x(), c.y()) = 100;
  }
}

void ExploreMap::Stamp(const Eigen::Vector2d& p) {
  const double res = grid_.resolution_m;
  const int r = static_cast<int>(std::ceil(options_.assume_free_radius_m / res));
  const Eigen::Vector2i c = grid_.CellOf(p);
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      if ((dx * dx + dy * dy) * res * res >
          options_.assume_free_radius_m * options_.assume_free_radius_m)
        continue;
      const int x = c.x() + dx, y = c.y() + dy;
      if (!grid_.Contains(x, y)) continue;
      if (grid_.at(x, y) < 0) grid_.at(x, y) = 0;
      // Only the body's own cells are seen; the rest of the stamp is assumed.
      if ((dx * dx + dy * dy) * res * res <= options_.robot_radius_m * options_.robot_radius_m)
        viewed_[grid_.Index(x, y)] = 1;
    }
  }
}

bool ExploreMap::Seen(int x, int y) const {
  return grid_.Contains(x, y) && !viewed_.empty() && viewed_[grid_.Index(x, y)] != 0;
}

void ExploreMap::AddTrail(const Eigen::Vector2d& position_m) {
  if (!trail_.empty() && (trail_.back() - position_m).norm() < 0.1) return;
  trail_.push_back(position_m);
  if (has_map()) Stamp(position_m);
}

void ExploreMap::IntegrateScan(const common::Rigid2d& map_from_base, const Scan& scan) {
  if (!has_map()) return;
  const double res = grid_.resolution_m;
  const Eigen::Vector2d origin = map_from_base.translation();
  scan_range_min_m_ = scan.range_min_m;
  const bool with_visibility = scan.visible_from_m.size() == scan.ranges_m.size();
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    bool hit = false;
    double length = 0;
    if (std::isinf(r) && r > 0) {
      length = scan.range_max_m;
    } else if (std::isfinite(r) && r >= scan.range_min_m && r <= scan.range_max_m) {
      length = r;
      hit = true;
    }
    const double angle = map_from_base.yaw_rad() + scan.angle_min_rad +
                         scan.angle_increment_rad * static_cast<double>(i);
    const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
    // The sensor looked along the beam over the near field beyond its minimum range (up to
    // the return), also when the beam carries no information; MAP says what is further.
    const double near_m = scan.range_min_m + kNearFieldM;
    const double looked_m = length > 0 ? std::min(length, near_m) : near_m;
    for (double t = scan.range_min_m; t <= looked_m; t += 0.5 * res) {
      const Eigen::Vector2i c = grid_.CellOf(origin + dir * t);
      if (!grid_.Contains(c.x(), c.y())) break;
      viewed_[grid_.Index(c.x(), c.y())] = 1;
    }
    if (length <= 0) continue;  // no information
    // Free up to one cell short of the return, sampled at half a cell.
    const int steps = static_cast<int>((length - (hit ? res : 0.0)) / (0.5 * res));
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector2i c = grid_.CellOf(origin + dir * (0.5 * res * k));
      if (!grid_.Contains(c.x(), c.y())) break;
      const int index = grid_.Index(c.x(), c.y());
      int8_t& v = grid_.at(c.x(), c.y());
      // An own return nearer than the range from which its surface is in view: the ray passed
      // over it (rubble before a depth camera), not through.
      if (hit_[index] && 0.5 * res * k < hit_visible_from_m_[index]) continue;
      // Unknown, uncertain, or one of the explorer's own returns that is no longer there: the
      // ray passed. MAP's obstacles stay (the next MAP is the judge of those).
      if (v < options_.occupied_threshold || hit_[index]) {
        v = 0;
        crossed_[index] = 1;
        hit_[index] = 0;
        hit_visible_from_m_[index] = 0;
      }
    }
    if (hit) {
      const Eigen::Vector2i c = grid_.CellOf(origin + dir * length);
      if (grid_.Contains(c.x(), c.y())) {
        const int index = grid_.Index(c.x(), c.y());
        int8_t& v = grid_.at(c.x(), c.y());
        const float visible_from =
            with_visibility ? scan.visible_from_m[i] : static_cast<float>(scan.range_min_m);
        if (v < options_.occupied_threshold || hit_[index]) {
          v = 100;
          hit_visible_from_m_[index] =
              hit_[index] ? std::max(hit_visible_from_m_[index], visible_from) : visible_from;
          hit_[index] = 1;
        }
        crossed_[index] = 0;
      }
    }
  }
}

void ExploreMap::UpdateCostMap() {
  // Chamfer distance transform (weights 1 and sqrt 2, two passes), in cells.
  const int w = grid_.width, h = grid_.height;
  std::vector<float> d(static_cast<size_t>(w) * h, kInf);
  for (size_t i = 0; i < d.size(); ++i) {
    if (grid_.cells[i] >= options_.occupied_threshold) d[i] = 0;
  }
  const float diag = static_cast<float>(M_SQRT2);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float& v = d[static_cast<size_t>(y) * w + x];
      if (x > 0) v = std::min(v, d[static_cast<size_t>(y) * w + x - 1] + 1);
      if (y > 0) {
        v = std::min(v, d[static_cast<size_t>(y - 1) * w + x] + 1);
        if (x > 0) v = std::min(v, d[static_cast<size_t>(y - 1) * w + x - 1] + diag);
        if (x + 1 < w) v = std::min(v, d[static_cast<size_t>(y - 1) * w + x + 1] + diag);
      }
    }
  }
  for (int y = h - 1; y >= 0; --y) {
    for (int x = w - 1; x >= 0; --x) {
      float& v = d[static_cast<size_t>(y) * w + x];
      if (x + 1 < w) v = std::min(v, d[static_cast<size_t>(y) * w + x + 1] + 1);
      if (y + 1 < h) {
        v = std::min(v, d[static_cast<size_t>(y + 1) * w + x] + 1);
        if (x + 1 < w) v = std::min(v, d[static_cast<size_t>(y + 1) * w + x + 1] + diag);
        if (x > 0) v = std::min(v, d[static_cast<size_t>(y + 1) * w + x - 1] + diag);
      }
    }
  }
  // Distance between cell centres understates the clearance by up to half a cell of the
  // obstacle cell itself; take the obstacle's edge, not its centre.
  const float res = static_cast<float>(grid_.resolution_m);
  for (float& v : d) v = std::isfinite(v) ? std::max(0.0f, (v - 0.5f) * res) : 1e6f;
  distance_m_ = std::move(d);
}

double ExploreMap::Clearance(int x, int y) const {
  if (!grid_.Contains(x, y) || distance_m_.empty()) return 0;
  return distance_m_[grid_.Index(x, y)];
}

bool ExploreMap::Traversable(int x, int y) const {
  if (!grid_.Contains(x, y) || distance_m_.empty()) return false;
  const int8_t v = grid_.at(x, y);
  return v >= 0 && v < options_.free_threshold &&
         distance_m_[grid_.Index(x, y)] >= options_.robot_radius_m;
}

bool ExploreMap::Traversable(const Eigen::Vector2d& p) const {
  const Eigen::Vector2i c = grid_.CellOf(p);
  return Traversable(c.x(), c.y());
}

bool ExploreMap::Occupied(const Eigen::Vector2d& p) const {
  const Eigen::Vector2i c = grid_.CellOf(p);
  return grid_.Contains(c.x(), c.y()) && grid_.at(c.x(), c.y()) >= options_.occupied_threshold;
}

bool ExploreMap::Known(const Eigen::Vector2d& p) const {
  const Eigen::Vector2i c = grid_.CellOf(p);
  return grid_.Contains(c.x(), c.y()) && grid_.at(c.x(), c.y()) >= 0;
}

bool ExploreMap::LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  const double length = (b - a).norm();
  const int steps = static_cast<int>(length / (0.5 * grid_.resolution_m)) + 1;
  for (int k = 0; k <= steps; ++k) {
    if (Occupied(a + (b - a) * (static_cast<double>(k) / steps))) return false;
  }
  return true;
}

double ExploreMap::SegmentClearance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  const double length = (b - a).norm();
  const int steps = static_cast<int>(length / (0.5 * grid_.resolution_m)) + 1;
  double least = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= steps; ++k) {
    const Eigen::Vector2i c = grid_.CellOf(a + (b - a) * (static_cast<double>(k) / steps));
    least = std::min(least, Clearance(c.x(), c.y()));
  }
  return least;
}

double ExploreMap::StepCost(int index) const {
  const double free_room = distance_m_[index] - options_.robot_radius_m;
  const double tight =
      options_.clearance_m > 0 ? std::max(0.0, 1.0 - free_room / options_.clearance_m) : 0.0;
  return 1.0 + options_.clearance_weight * tight;
}

CostField ExploreMap::Plan(const Eigen::Vector2d& from, double escape_m) const {
  CostField field;
  const size_t n = grid_.cells.size();
  field.cost.assign(n, kInf);
  field.parent.assign(n, -1);
  if (!has_map() || distance_m_.size() != n) return field;
  Eigen::Vector2i start = grid_.CellOf(from);
  float start_cost = 0;
  if (!Traversable(start.x(), start.y())) {
    // The nearest traversable cell within escape_m, driven to in a straight line.
    const int r = static_cast<int>(std::ceil(escape_m / grid_.resolution_m));
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2i best_cell = start;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const double dist = std::hypot(dx, dy) * grid_.resolution_m;
        if (dist > escape_m || dist >= best || !Traversable(start.x() + dx, start.y() + dy))
          continue;
        best = dist;
        best_cell = start + Eigen::Vector2i(dx, dy);
      }
    }
    if (!std::isfinite(best)) return field;
    start = best_cell;
    start_cost = static_cast<float>(best);
  }
  field.start = start;
  field.valid = true;
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  const int s = grid_.Index(start.x(), start.y());
  field.cost[s] = start_cost;
  open.push({start_cost, s});
  const float res = static_cast<float>(grid_.resolution_m);
  while (!open.empty()) {
    const auto [c, i] = open.top();
    open.pop();
    if (c > field.cost[i]) continue;
    const int x = i % grid_.width, y = i / grid_.width;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const int nx = x + dx, ny = y + dy;
        if (!Traversable(nx, ny)) continue;
        const int j = grid_.Index(nx, ny);
        const float step =
            (dx && dy ? static_cast<float>(M_SQRT2) : 1.0f) * res * static_cast<float>(StepCost(j));
        if (c + step < field.cost[j]) {
          field.cost[j] = c + step;
          field.parent[j] = i;
          open.push({c + step, j});
        }
      }
    }
  }
  return field;
}

std::vector<Eigen::Vector2d> ExploreMap::PathTo(const CostField& field,
                                                const Eigen::Vector2d& goal) const {
  std::vector<Eigen::Vector2d> path;
  const Eigen::Vector2i g = grid_.CellOf(goal);
  if (!grid_.Contains(g.x(), g.y())) return path;
  const int gi = grid_.Index(g.x(), g.y());
  if (!field.Reached(gi)) return path;
  for (int i = gi; i >= 0; i = field.parent[i])
    path.push_back(grid_.CentreOf(i % grid_.width, i / grid_.width));
  std::reverse(path.begin(), path.end());
  return path;
}

double ExploreMap::TrailReachedFraction(const CostField& field, double tolerance_m) const {
  int samples = 0, reached = 0;
  const int r = static_cast<int>(std::ceil(tolerance_m / grid_.resolution_m));
  std::optional<Eigen::Vector2d> last;
  for (const Eigen::Vector2d& p : trail_) {
    if (last && (p - *last).norm() < 1.0) continue;
    last = p;
    ++samples;
    const Eigen::Vector2i c = grid_.CellOf(p);
    bool found = false;
    for (int dy = -r; dy <= r && !found; ++dy) {
      for (int dx = -r; dx <= r && !found; ++dx) {
        if (!grid_.Contains(c.x() + dx, c.y() + dy) || (dx * dx + dy * dy) > r * r) continue;
        found = field.Reached(grid_.Index(c.x() + dx, c.y() + dy));
      }
    }
    reached += found;
  }
  return samples < 3 ? 1.0 : static_cast<double>(reached) / samples;
}

std::vector<Frontier> ExploreMap::Frontiers(const CostField& field) const {
  std::vector<Frontier> out;
  if (!has_map()) return out;
  const auto is_frontier = [&](int x, int y) {
    if (!field.Reached(grid_.Index(x, y))) return false;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (!grid_.Contains(x + dx, y + dy)) continue;
        const int8_t v = grid_.at(x + dx, y + dy);
        // Unknown, or seen too little to call free or occupied.
        if (v < 0 || (v >= options_.free_threshold && v < options_.occupied_threshold)) return true;
      }
    }
    return false;
  };
  std::vector<uint8_t> seen(grid_.cells.size(), 0);
  for (int y = 0; y < grid_.height; ++y) {
    for (int x = 0; x < grid_.width; ++x) {
      const int i = grid_.Index(x, y);
      if (seen[i] || !field.Reached(i) || !is_frontier(x, y)) continue;
      Frontier f;
      std::queue<Eigen::Vector2i> todo;
      todo.push({x, y});
      seen[i] = 1;
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      while (!todo.empty()) {
        const Eigen::Vector2i c = todo.front();
        todo.pop();
        f.cells.push_back(c);
        sum += grid_.CentreOf(c.x(), c.y());
        const double cc = field.cost[grid_.Index(c.x(), c.y())];
        if (cc < best) {
          best = cc;
          f.goal_m = grid_.CentreOf(c.x(), c.y());
        }
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = c.x() + dx, ny = c.y() + dy;
            if (!grid_.Contains(nx, ny)) continue;
            const int j = grid_.Index(nx, ny);
            if (!seen[j] && is_frontier(nx, ny)) {
              seen[j] = 1;
              todo.push({nx, ny});
            }
          }
        }
      }
      if (static_cast<int>(f.cells.size()) < options_.min_frontier_cells) continue;
      f.centroid_m = sum / static_cast<double>(f.cells.size());
      f.path_cost_m = best;
      f.size_m = grid_.resolution_m * static_cast<double>(f.cells.size());
      out.push_back(std::move(f));
    }
  }
  return out;
}

}  // namespace explore
}  // namespace sarmap
