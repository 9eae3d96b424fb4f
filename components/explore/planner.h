#pragma once
// The planning side of sarmap-explore, free of LCM: the explorer's own picture of the site
// (SLAM's MAP, refreshed between maps by the latest scans and the robot's own trail), the
// cost map the robot plans on, a Dijkstra planner, and frontiers.
//
// Cost map. d(c) is the distance from cell c to the nearest occupied cell (chamfer distance
// transform, 3-4 weights). A cell is traversable when it is known free and d(c) >= robot
// radius; each step into it costs its length times
//   1 + clearance_weight * max(0, 1 - (d(c) - r_robot) / clearance_m),
// so paths keep away from walls where there is room and still pass doors.
// Frontiers (Yamauchi 1997): traversable cells with an unknown 8-neighbour (or one seen too
// little to be called free or occupied), grouped
// 8-connected; a frontier is reachable when the planner reaches one of its cells.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "common/options.h"
#include "common/transform.h"

namespace sarmap {
namespace explore {

// A planar laser scan in the base frame. Ranges: finite in [range_min, range_max] a return;
// +inf no return (free up to range_max); 0 or NaN no information.
struct Scan {
  double stamp_s = 0;  // sensor time, on the clock of the POSE stamps
  double angle_min_rad = 0;
  double angle_increment_rad = 0;
  double range_min_m = 0;
  double range_max_m = 0;
  std::vector<float> ranges_m;
  // Per beam (or empty): the nearest range at which a return's surface is in the sensor's
  // view. A depth camera looks over low objects close by, so a ray that passes a cell nearer
  // than this is no sign that an obstacle seen there is gone. Empty: every return is seen
  // down to range_min_m (a laser).
  std::vector<float> visible_from_m;
};

struct Grid {
  int width = 0, height = 0;
  double resolution_m = 0.05;
  double origin_x_m = 0, origin_y_m = 0;  // cell (0, 0) corner; the grid is axis-aligned
  std::vector<int8_t> cells;              // -1 unknown, 0..100 occupancy, row-major
  int8_t at(int x, int y) const { return cells[static_cast<size_t>(y) * width + x]; }
  int8_t& at(int x, int y) { return cells[static_cast<size_t>(y) * width + x]; }
  bool Contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  Eigen::Vector2i CellOf(const Eigen::Vector2d& p) const;
  Eigen::Vector2d CentreOf(int x, int y) const;
  int Index(int x, int y) const { return y * width + x; }
};

struct PlannerOptions {
  double robot_radius_m = 0.25;
  double clearance_m = 0.35;           // extra clearance the cost prefers beyond the radius
  double clearance_weight = 4.0;       // cost factor at the radius (1 + weight)
  int free_threshold = 25;             // cells below are free
  int occupied_threshold = 65;         // cells at or above are obstacles
  int min_frontier_cells = 4;          // smaller frontiers are noise
  double pad_m = 4.0;                  // the explorer's grid extends MAP this far on each side
  double assume_free_radius_m = 0.45;  // around every pose the robot has been: its body was there
  double glass_join_m = 3.0;           // two contacts in line this close are one invisible surface
  double glass_extend_m = 4.0;         // such a surface is extended along its line up to this far
  template <class V>
  void Visit(V& v) {
    v("robot_radius_m", robot_radius_m, "cells closer than this to an obstacle are not traversable",
      Positive());
    v("clearance_m", clearance_m, "paths prefer this much room beyond the radius", NonNegative());
    v("clearance_weight", clearance_weight, "cost factor of a step at the radius is 1 + this",
      NonNegative());
    v("free_threshold", free_threshold, "occupancy below this is free");
    v("occupied_threshold", occupied_threshold, "occupancy at or above this is an obstacle");
    v("min_frontier_cells", min_frontier_cells, "smaller frontiers are ignored", AtLeast(1));
    v("pad_m", pad_m, "the explorer's grid extends MAP by this on each side (scans fill it)",
      NonNegative());
    v("assume_free_radius_m", assume_free_radius_m,
      "unknown cells this close to any pose the robot has had are free (the camera cannot see its "
      "own footprint)",
      NonNegative());
    v("glass_join_m", glass_join_m,
      "two contacts in line (similar heading, each on the other's surface) this close are one "
      "invisible surface (glass)",
      NonNegative());
    v("glass_extend_m", glass_extend_m,
      "an invisible surface is extended along its line over seen-through cells, until an obstacle "
      "or this far",
      NonNegative());
  }
  void Validate(common::Validator& check) const {
    check.That(
        free_threshold >= 0 && free_threshold < occupied_threshold && occupied_threshold <= 100,
        "occupied_threshold", "need 0 <= free_threshold < occupied_threshold <= 100");
  }
};

struct Frontier {
  std::vector<Eigen::Vector2i> cells;
  Eigen::Vector2d goal_m = Eigen::Vector2d::Zero();  // its cell nearest the robot by path
  Eigen::Vector2d centroid_m = Eigen::Vector2d::Zero();
  double path_cost_m = 0;
  double size_m = 0;  // cells x resolution
};

// Dijkstra costs from one start over the cost map.
struct CostField {
  bool valid = false;  // a start cell was found
  Eigen::Vector2i start{0, 0};
  std::vector<float> cost;  // +inf where unreachable
  std::vector<int> parent;  // -1 at the start and where unreachable
  bool Reached(int index) const {
    return index >= 0 && index < static_cast<int>(cost.size()) && std::isfinite(cost[index]);
  }
};

class ExploreMap {
 public:
  explicit ExploreMap(const PlannerOptions& options) : options_(options) {}

  // A new MAP: the explorer's grid becomes it (padded), then what the explorer knows better
  // is laid over it: its own scan returns where MAP does not call the cell free, the cells its
  // rays crossed where MAP has no verdict (unknown, or seen too little), the trail, contacts.
  void SetMap(const Grid& map);
  // Between maps: cells along each ray that are not MAP obstacles become free (a return of
  // an earlier scan that a ray now crosses is gone), a return marks its cell occupied
  // (something new in the way). +inf rays are free to range_max; rays without information
  // are skipped.
  void IntegrateScan(const common::Rigid2d& map_from_base, const Scan& scan);
  // The robot is at this pose: unknown cells within assume_free_radius_m are free.
  void AddTrail(const Eigen::Vector2d& position_m);
  // An obstacle the sensors do not see (glass, a low step) found by running into it: a segment
  // across the robot's front, kept as occupied through every later MAP. Two contacts in line
  // make an invisible surface (a glass pane) that spans between them and beyond (GlassLine).
  // Returns false (no mark) when the map already has an obstacle at the robot's front: what
  // it touched is known.
  bool AddContact(const common::Rigid2d& map_from_base);
  int contacts() const { return static_cast<int>(contacts_.size()); }
  int glass_lines() const { return static_cast<int>(lines_.size()); }
  // Forgets the contacts and surfaces that bound the region the field reaches (the robot is
  // shut in by them) and redraws the grid from the last MAP without them; false if none did.
  bool ClearContactsBounding(const CostField& field);
  // Forgets the contacts that are not part of an invisible surface (a bump into something
  // once) and redraws; false if there were none.
  bool ClearLoneContacts();

  // Rebuilds the distance transform and traversability (after SetMap / IntegrateScan).
  void UpdateCostMap();
  bool Traversable(int x, int y) const;
  bool Traversable(const Eigen::Vector2d& p) const;
  // Distance (m) from the cell to the nearest obstacle; large where none is near.
  double Clearance(int x, int y) const;
  bool Occupied(const Eigen::Vector2d& p) const;
  // The cell was seen: MAP knows it, one of the explorer's own scans looked at it from beyond
  // the sensor's minimum range, or the robot's body (robot_radius_m) stood on it. Cells
  // assume_free_radius_m calls free around the trail are not seen.
  bool Seen(int x, int y) const;
  bool Known(const Eigen::Vector2d& p) const;
  // No obstacle cell on the segment (unknown cells do not block).
  bool LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  // The least Clearance of the cells along the segment (sampled every half cell).
  double SegmentClearance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;

  // Dijkstra from `from`. When `from` is not traversable (the robot brushed a wall, or stands
  // in a cell the map calls occupied), the search starts from the nearest traversable cell
  // within escape_m, reached in a straight line; `valid` is false when there is none.
  CostField Plan(const Eigen::Vector2d& from, double escape_m = 1.0) const;
  // The path to `goal` in the field (start first), or empty when unreachable.
  std::vector<Eigen::Vector2d> PathTo(const CostField& field, const Eigen::Vector2d& goal) const;
  // The share of the trail (sampled every metre) with a cell the field reaches within
  // tolerance_m; 1 when the trail is shorter than three samples.
  double TrailReachedFraction(const CostField& field, double tolerance_m) const;
  // Reachable frontiers, unsorted, each with its cheapest cell as goal.
  std::vector<Frontier> Frontiers(const CostField& field) const;

  const Grid& grid() const { return grid_; }
  bool has_map() const { return grid_.width > 0; }
  const PlannerOptions& options() const { return options_; }

 private:
  void Stamp(const Eigen::Vector2d& p);
  double StepCost(int index) const;

  PlannerOptions options_;
  Grid grid_;
  Grid last_map_;  // the last MAP as received
  // 1 where a ray of the explorer's own scans crossed the cell since its last return there.
  // SLAM renders a room looked into from its door once or twice as "seen too little"; the
  // scans that crossed it are what the explorer plans through.
  std::vector<uint8_t> crossed_;
  // 1 where one of the explorer's own scan returns marked the cell and no later ray crossed it.
  std::vector<uint8_t> hit_;
  // Per own return: the nearest range from which its surface is in view (Scan::visible_from_m).
  std::vector<float> hit_visible_from_m_;
  // 1 where the cell was seen (Seen()).
  std::vector<uint8_t> viewed_;
  double scan_range_min_m_ = 0;    // the latest scan's
  std::vector<float> distance_m_;  // to the nearest obstacle
  std::vector<Eigen::Vector2d> trail_;
  std::vector<common::Rigid2d> contacts_;
  std::vector<bool> in_line_;  // per contact: one end of a GlassLine
  // An invisible surface inferred from contacts in line, from a_m to b_m (map frame).
  struct GlassLine {
    Eigen::Vector2d a_m, b_m;
    bool extended = false;
  };
  std::vector<GlassLine> lines_;
  void StampContact(const common::Rigid2d& map_from_base);
  void StampLine(GlassLine& line);
  // No MAP obstacle cell on the segment.
  bool NoObstacleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
};

}  // namespace explore
}  // namespace sarmap
