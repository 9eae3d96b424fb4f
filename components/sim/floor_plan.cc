#include "sim/floor_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/robot.h"

namespace sarmap {
namespace sim {
namespace {

bool InBand(double base_m, double top_m, const FloorPlanOptions& o) {
  return top_m > o.min_height_m && base_m < o.max_height_m;
}

// Marks the cells whose centres lie inside a rectangle (centre, half sizes, yaw).
void FillRectangle(GridMap* g, const Eigen::Vector2d& centre, const Eigen::Vector2d& half, double yaw,
                   int8_t value) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double rx = std::abs(c) * half.x() + std::abs(s) * half.y();
  const double ry = std::abs(s) * half.x() + std::abs(c) * half.y();
  const int x0 = std::max(0, static_cast<int>(std::floor((centre.x() - rx - g->origin_x_m) / g->resolution_m)));
  const int x1 = std::min(g->width - 1, static_cast<int>(std::floor((centre.x() + rx - g->origin_x_m) / g->resolution_m)));
  const int y0 = std::max(0, static_cast<int>(std::floor((centre.y() - ry - g->origin_y_m) / g->resolution_m)));
  const int y1 = std::min(g->height - 1, static_cast<int>(std::floor((centre.y() + ry - g->origin_y_m) / g->resolution_m)));
  // A thin obstacle (a 10 cm wall on a 5 cm grid) must still cover a cell across its width.
  const double pad = 0.5 * g->resolution_m;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p(g->origin_x_m + (x + 0.5) * g->resolution_m, g->origin_y_m + (y + 0.5) * g->resolution_m);
      const Eigen::Vector2d d = p - centre;
      const double u = c * d.x() + s * d.y(), v = -s * d.x() + c * d.y();
      if (std::abs(u) <= half.x() + pad && std::abs(v) <= half.y() + pad) g->cells[y * g->width + x] = value;
    }
  }
}

bool HasNear(const GridMap& g, int x, int y, int r, int8_t value) {
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if (xx < 0 || yy < 0 || xx >= g.width || yy >= g.height) continue;
      if (g.cells[yy * g.width + xx] == value) return true;
    }
  }
  return false;
}

constexpr int8_t kGlass = 50;  // an occupied cell of the floor plan made of glass (internal mark)

GridMap Rasterise(const World& world, const FloorPlanOptions& o, double resolution_m, const Eigen::Vector2d& origin_m,
                  int width, int height, bool mark_glass) {
  GridMap g;
  g.resolution_m = resolution_m;
  g.width = width;
  g.height = height;
  g.origin_x_m = origin_m.x();
  g.origin_y_m = origin_m.y();
  g.cells.assign(static_cast<size_t>(width) * height, 0);
  for (const Wall& w : world.walls) {
    if (!InBand(w.base_m, w.base_m + w.height_m, o)) continue;
    const Eigen::Vector2d along = w.to - w.from;
    const double length = along.norm();
    if (length <= 0) continue;
    FillRectangle(&g, 0.5 * (w.from + w.to), Eigen::Vector2d(0.5 * length, 0.5 * w.thickness_m),
                  std::atan2(along.y(), along.x()), w.glass && mark_glass ? kGlass : 100);
  }
  for (const Box& b : world.boxes) {
    if (!InBand(b.base_m, b.base_m + b.size_m.z(), o)) continue;
    FillRectangle(&g, b.centre, 0.5 * b.size_m.head<2>(), b.yaw_rad, 100);
  }
  for (const Table& t : world.tables) {
    if (InBand(t.height_m - t.top_thickness_m, t.height_m, o)) {
      FillRectangle(&g, t.centre, 0.5 * t.size_m, t.yaw_rad, 100);
      continue;
    }
    // Only the legs reach into the band: one at each corner.
    const double c = std::cos(t.yaw_rad), s = std::sin(t.yaw_rad);
    for (int sx : {-1, 1}) {
      for (int sy : {-1, 1}) {
        const Eigen::Vector2d local(sx * (0.5 * t.size_m.x() - t.leg_width_m), sy * (0.5 * t.size_m.y() - t.leg_width_m));
        const Eigen::Vector2d at = t.centre + Eigen::Vector2d(c * local.x() - s * local.y(), s * local.x() + c * local.y());
        FillRectangle(&g, at, Eigen::Vector2d(0.5 * t.leg_width_m, 0.5 * t.leg_width_m), t.yaw_rad, 100);
      }
    }
  }
  return g;
}

struct Truth {
  GridMap grid;
  Eigen::Vector2d lo, hi;  // the site: the walls' bounding box
  bool valid = false;
};

Truth MakeTruth(const World& world, const FloorPlanOptions& o, double r) {
  Truth t;
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const Wall& w : world.walls) {
    lo = lo.cwiseMin(w.from).cwiseMin(w.to);
    hi = hi.cwiseMax(w.from).cwiseMax(w.to);
  }
  if (lo.x() > hi.x()) return t;
  const double margin = 1.0;
  const Eigen::Vector2d origin = lo - Eigen::Vector2d(margin, margin);
  const int width = static_cast<int>(std::ceil((hi.x() - lo.x() + 2 * margin) / r));
  const int height = static_cast<int>(std::ceil((hi.y() - lo.y() + 2 * margin) / r));
  t.grid = Rasterise(world, o, r, origin, width, height, true);
  t.lo = lo;
  t.hi = hi;
  t.valid = true;
  return t;
}

MapAgreement Compare(const GridMap& map, const World& world, const Truth& t, const Eigen::Vector3d& world_from_map,
                     const FloorPlanOptions& o) {
  MapAgreement out;
  out.world_from_map = world_from_map;
  if (!t.valid || map.width <= 0 || map.height <= 0) return out;
  const GridMap& truth = t.grid;
  const double r = map.resolution_m;
  const double c = std::cos(world_from_map.z()), s = std::sin(world_from_map.z());
  for (int my = 0; my < map.height; ++my) {
    for (int mx = 0; mx < map.width; ++mx) {
      const int v = map.cells[my * map.width + mx];
      if (v < 0 || (v > o.free_threshold && v < o.occupied_threshold)) continue;  // unknown
      const double px = map.origin_x_m + (mx + 0.5) * r, py = map.origin_y_m + (my + 0.5) * r;
      const Eigen::Vector2d w(world_from_map.x() + c * px - s * py, world_from_map.y() + s * px + c * py);
      bool near_person = false;
      for (const Person& p : world.people) near_person = near_person || (w - p.position).norm() < o.person_exclusion_m;
      if (near_person) continue;
      const bool occupied = v >= o.occupied_threshold;
      const int tx = static_cast<int>(std::floor((w.x() - truth.origin_x_m) / truth.resolution_m));
      const int ty = static_cast<int>(std::floor((w.y() - truth.origin_y_m) / truth.resolution_m));
      // Outside the site (beyond its walls' bounding box) nothing exists: a map that claims to
      // know space there is misplaced or wrong there.
      const bool inside = w.x() >= t.lo.x() && w.y() >= t.lo.y() && w.x() <= t.hi.x() && w.y() <= t.hi.y();
      const bool agrees = inside && (occupied ? (HasNear(truth, tx, ty, o.tolerance_cells, 100) ||
                                                 HasNear(truth, tx, ty, o.tolerance_cells, kGlass))
                                              : HasNear(truth, tx, ty, o.tolerance_cells, 0));
      ++out.known_cells;
      out.agreeing_cells += agrees;
      (occupied ? out.occupied_known : out.free_known) += 1;
      (occupied ? out.occupied_agreeing : out.free_agreeing) += agrees;
      if (inside && truth.cells[ty * truth.width + tx] == kGlass) {
        ++out.glass_cells;
        out.glass_cells_seen_free += !occupied;
      }
    }
  }
  return out;
}

// Calls f(x, y, distance) for every cell whose centre is within `reach` of the segment
// [a, b], with its distance to the segment.
template <class F>
void ForCellsNear(const GridMap& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double reach, F f) {
  const Eigen::Vector2d pad(reach, reach);
  const Eigen::Vector2d lo = a.cwiseMin(b) - pad, hi = a.cwiseMax(b) + pad;
  const double res = g.resolution_m;
  const int x0 = std::max(0, static_cast<int>(std::floor((lo.x() - g.origin_x_m) / res)));
  const int x1 = std::min(g.width - 1, static_cast<int>(std::floor((hi.x() - g.origin_x_m) / res)));
  const int y0 = std::max(0, static_cast<int>(std::floor((lo.y() - g.origin_y_m) / res)));
  const int y1 = std::min(g.height - 1, static_cast<int>(std::floor((hi.y() - g.origin_y_m) / res)));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p(g.origin_x_m + (x + 0.5) * res, g.origin_y_m + (y + 0.5) * res);
      const double d = SegmentDistance(p, a, b);
      if (d < reach) f(x, y, d);
    }
  }
}

// The cells covered by what stops the robot, drawn with their true shapes: walls, boxes, table
// legs and low table tops (CollisionObstacles() models the same things for collisions), and
// people when `with_people`. A cell is covered when its centre lies on the shape, each side
// taken at least one cell wide so that a thin leg still covers a cell.
std::vector<uint8_t> Footprint(const World& world, const GridMap& grid, bool with_people) {
  GridMap g = grid;
  g.cells.assign(grid.cells.size(), 0);
  const double min_half = 0.5 * g.resolution_m + 1e-9;  // a leg on a cell border covers both cells
  const auto fill = [&](const Eigen::Vector2d& centre, Eigen::Vector2d half, double yaw) {
    half = half.cwiseMax(Eigen::Vector2d(min_half, min_half));
    const double pad = -0.5 * g.resolution_m;  // FillRectangle pads by this plus half a cell
    FillRectangle(&g, centre, half + Eigen::Vector2d(pad, pad), yaw, 1);
  };
  for (const Wall& w : world.walls) {
    if (w.base_m >= kRobotHeightM) continue;
    const Eigen::Vector2d along = w.to - w.from;
    fill(0.5 * (w.from + w.to), Eigen::Vector2d(0.5 * along.norm(), 0.5 * w.thickness_m),
         std::atan2(along.y(), along.x()));
  }
  for (const Box& b : world.boxes) {
    if (b.base_m < kRobotHeightM) fill(b.centre, 0.5 * b.size_m.head<2>(), b.yaw_rad);
  }
  for (const Table& t : world.tables) {
    if (t.height_m - t.top_thickness_m < kRobotHeightM) {
      fill(t.centre, 0.5 * t.size_m, t.yaw_rad);
      continue;
    }
    const Eigen::Vector2d ax(std::cos(t.yaw_rad), std::sin(t.yaw_rad)), ay(-ax.y(), ax.x());
    for (double sx : {-1.0, 1.0}) {
      for (double sy : {-1.0, 1.0}) {
        const Eigen::Vector2d c = t.centre + ax * sx * (t.size_m.x() / 2 - t.leg_width_m) +
                                  ay * sy * (t.size_m.y() / 2 - t.leg_width_m);
        fill(c, Eigen::Vector2d(0.5 * t.leg_width_m, 0.5 * t.leg_width_m), t.yaw_rad);
      }
    }
  }
  std::vector<uint8_t> out(g.cells.begin(), g.cells.end());
  if (with_people) {
    for (const Person& p : world.people) {
      const double r = p.posture == Posture::kLying ? 0.5 : 0.25;
      ForCellsNear(g, p.position, p.position, r, [&](int x, int y, double) { out[static_cast<size_t>(y) * g.width + x] = 1; });
    }
  }
  return out;
}

}  // namespace

GridMap ReachableFloor(const World& world, double robot_radius_m, double resolution_m, bool people_block) {
  const std::vector<Obstacle> obstacles = CollisionObstacles(world, people_block);
  const Eigen::Vector2d start = world.robot.pose.head<2>();
  Eigen::Vector2d lo = start, hi = start;
  for (const Obstacle& o : obstacles) {
    const Eigen::Vector2d pad(o.half_width, o.half_width);
    lo = lo.cwiseMin(o.a.cwiseMin(o.b) - pad).eval();
    hi = hi.cwiseMax(o.a.cwiseMax(o.b) + pad).eval();
  }
  const double margin = robot_radius_m + 2 * resolution_m;
  GridMap g;
  g.resolution_m = resolution_m;
  g.origin_x_m = lo.x() - margin;
  g.origin_y_m = lo.y() - margin;
  g.width = static_cast<int>(std::ceil((hi.x() - lo.x() + 2 * margin) / resolution_m));
  g.height = static_cast<int>(std::ceil((hi.y() - lo.y() + 2 * margin) / resolution_m));
  const size_t n = static_cast<size_t>(g.width) * g.height;
  g.cells.assign(n, -1);
  // A centre is blocked where the robot's disc would collide (robot.cc's test, at the cell
  // centre).
  std::vector<uint8_t> blocked(n, 0), covered(n, 0);
  for (const Obstacle& o : obstacles) {
    ForCellsNear(g, o.a, o.b, robot_radius_m + o.half_width,
                 [&](int x, int y, double) { blocked[static_cast<size_t>(y) * g.width + x] = 1; });
  }
  const std::vector<uint8_t> footprint = Footprint(world, g, people_block);
  // Centres reachable from the start: flood fill over unblocked cells.
  const int sx = static_cast<int>(std::floor((start.x() - g.origin_x_m) / resolution_m));
  const int sy = static_cast<int>(std::floor((start.y() - g.origin_y_m) / resolution_m));
  std::vector<uint8_t> reached(n, 0);
  std::vector<int> frontier;
  if (sx >= 0 && sy >= 0 && sx < g.width && sy < g.height && !blocked[sy * g.width + sx]) {
    reached[sy * g.width + sx] = 1;
    frontier.push_back(sy * g.width + sx);
  }
  while (!frontier.empty()) {
    const int i = frontier.back();
    frontier.pop_back();
    const int x = i % g.width, y = i / g.width;
    const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
    for (const auto& q : next) {
      if (q[0] < 0 || q[1] < 0 || q[0] >= g.width || q[1] >= g.height) continue;
      const int j = q[1] * g.width + q[0];
      if (reached[j] || blocked[j]) continue;
      reached[j] = 1;
      frontier.push_back(j);
    }
  }
  // The body: every cell within robot_radius_m of a reachable centre. Inside the reachable set
  // the centres cover themselves, so only its boundary cells stamp their disc.
  const int rc = static_cast<int>(std::ceil(robot_radius_m / resolution_m));
  std::vector<std::pair<int, int>> disc;
  for (int dy = -rc; dy <= rc; ++dy) {
    for (int dx = -rc; dx <= rc; ++dx) {
      if ((dx * dx + dy * dy) * resolution_m * resolution_m <= robot_radius_m * robot_radius_m) disc.emplace_back(dx, dy);
    }
  }
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int i = y * g.width + x;
      if (!reached[i]) continue;
      covered[i] = 1;
      const bool edge = x == 0 || y == 0 || x == g.width - 1 || y == g.height - 1 || !reached[i - 1] ||
                        !reached[i + 1] || !reached[i - g.width] || !reached[i + g.width];
      if (!edge) continue;
      for (const auto& d : disc) {
        const int xx = x + d.first, yy = y + d.second;
        if (xx >= 0 && yy >= 0 && xx < g.width && yy < g.height) covered[yy * g.width + xx] = 1;
      }
    }
  }
  for (size_t i = 0; i < n; ++i) g.cells[i] = footprint[i] ? 100 : covered[i] ? 0 : -1;
  return g;
}

double FloorArea(const GridMap& grid) {
  const auto free_cells = std::count(grid.cells.begin(), grid.cells.end(), static_cast<int8_t>(0));
  return static_cast<double>(free_cells) * grid.resolution_m * grid.resolution_m;
}

int CellAt(const GridMap& grid, const Eigen::Vector2d& p) {
  const int x = static_cast<int>(std::floor((p.x() - grid.origin_x_m) / grid.resolution_m));
  const int y = static_cast<int>(std::floor((p.y() - grid.origin_y_m) / grid.resolution_m));
  if (x < 0 || y < 0 || x >= grid.width || y >= grid.height) return -1;
  return grid.cells[static_cast<size_t>(y) * grid.width + x];
}

GridMap RasteriseFloorPlan(const World& world, const FloorPlanOptions& options, double resolution_m,
                           const Eigen::Vector2d& origin_m, int width, int height) {
  return Rasterise(world, options, resolution_m, origin_m, width, height, false);
}

MapAgreement CompareWithFloorPlan(const GridMap& map, const World& world, const Eigen::Vector3d& world_from_map,
                                  const FloorPlanOptions& o) {
  return Compare(map, world, MakeTruth(world, o, map.resolution_m), world_from_map, o);
}

MapAgreement BestFitAgreement(const GridMap& map, const World& world, const Eigen::Vector3d& world_from_map,
                              const FloorPlanOptions& options, double search_m, double search_rad) {
  const Truth truth = MakeTruth(world, options, map.resolution_m);
  MapAgreement best = Compare(map, world, truth, world_from_map, options);
  const int n_xy = static_cast<int>(std::floor(search_m / map.resolution_m + 1e-9));
  const double step_rad = 0.25 * M_PI / 180;
  const int n_yaw = static_cast<int>(std::floor(search_rad / step_rad + 1e-9));
  for (int k = -n_yaw; k <= n_yaw; ++k) {
    for (int i = -n_xy; i <= n_xy; ++i) {
      for (int j = -n_xy; j <= n_xy; ++j) {
        const Eigen::Vector3d pose = world_from_map + Eigen::Vector3d(i * map.resolution_m, j * map.resolution_m, k * step_rad);
        const MapAgreement a = Compare(map, world, truth, pose, options);
        if (a.agreement() > best.agreement()) best = a;
      }
    }
  }
  return best;
}

}  // namespace sim
}  // namespace sarmap
