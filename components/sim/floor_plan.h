#pragma once
// The true floor plan of a world at the height of the robot's scan, and how well a SLAM map
// agrees with it: the simulated acceptance of the mapping (Sales 2014 §5.1.1 compared its
// Kinect map with the ground truth pixel by pixel after a best-fit alignment, 94.3 %).
//
// Truth: a cell is occupied when an obstacle's footprint covers it and the obstacle reaches
// into the height band [min_height_m, max_height_m] above the floor (walls, glass panels —
// they are walls of the floor plan even though the depth camera sees through them —, boxes,
// table tops and legs); people are not part of the floor plan and cells near them are left out.
// Agreement: over the cells the map knows (occupied or free), the fraction whose state matches
// the truth within `tolerance_cells` (an occupied map cell agrees when a truly occupied cell is
// within that many cells, a free one when a truly free cell is; a known cell outside the site's
// walls never agrees). Free space dominates the count, so the agreement of the occupied cells
// alone is reported too: it is what a misplaced or bent map loses first.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "sim/world.h"

namespace sarmap {
namespace sim {

// A 2D grid in the world frame: cells row-major from the lower-left corner (as map_server),
// values 0 (free) .. 100 (occupied), -1 unknown.
struct GridMap {
  double resolution_m = 0.05;
  int width = 0, height = 0;
  double origin_x_m = 0, origin_y_m = 0;  // lower-left corner of cell (0, 0)
  std::vector<int8_t> cells;
};

struct FloorPlanOptions {
  double min_height_m = 0.05;   // the scan's height band (config/depth.yaml)
  double max_height_m = 1.0;
  double person_exclusion_m = 0.4;  // cells this close to a person are not compared
  int tolerance_cells = 1;
  int occupied_threshold = 65;  // map_server: occupied above, free below free_threshold
  int free_threshold = 25;
};

// True occupancy of the world on a grid of the given geometry (0 free, 100 occupied).
GridMap RasteriseFloorPlan(const World& world, const FloorPlanOptions& options, double resolution_m,
                           const Eigen::Vector2d& origin_m, int width, int height);

struct MapAgreement {
  int64_t known_cells = 0;       // compared (known in the map, not near a person)
  int64_t agreeing_cells = 0;
  int64_t occupied_known = 0, occupied_agreeing = 0;
  int64_t free_known = 0, free_agreeing = 0;
  int64_t glass_cells_seen_free = 0;  // truly glass, mapped free: the camera looked through
  int64_t glass_cells = 0;            // glass cells the map knows
  double agreement() const { return known_cells ? static_cast<double>(agreeing_cells) / known_cells : 0.0; }
  double occupied_agreement() const {
    return occupied_known ? static_cast<double>(occupied_agreeing) / occupied_known : 0.0;
  }
  Eigen::Vector3d world_from_map{0, 0, 0};  // x, y, yaw used
};

// The floor the robot's body can cover: the cells the robot's centre reaches from
// world.robot.pose through free space (a disc of robot_radius_m clear of every obstacle of
// CollisionObstacles(), the robot's own collision model: walls, glass, boxes, table legs and
// low table tops; people too when `people_block`), grown by robot_radius_m (the body around
// each reachable centre) and clipped to floor that no obstacle covers. Centres connect through
// the 4-neighbourhood of the grid, so a gap is passable when it is at least one cell wider
// than the robot's diameter plus the obstacles' half-widths. The grid covers the obstacles'
// bounding box (and the start) with a margin; frame = world frame, yaw 0. Values: 0 reachable
// floor, 100 obstacle footprint (cells whose centre is within max(half-width,
// resolution / sqrt(2)) of an obstacle's line), -1 neither (unreachable floor, outside the
// building). Nothing is reachable when the start pose itself collides.
GridMap ReachableFloor(const World& world, double robot_radius_m, double resolution_m = 0.05,
                       bool people_block = false);
// Area of the cells of value 0, m^2.
double FloorArea(const GridMap& grid);
// The value of the cell containing p; -1 outside the grid.
int CellAt(const GridMap& grid, const Eigen::Vector2d& p);

// Agreement of `map` (in its own frame) with the world's floor plan, the map placed in the
// world by `world_from_map` (x, y, yaw).
MapAgreement CompareWithFloorPlan(const GridMap& map, const World& world, const Eigen::Vector3d& world_from_map,
                                  const FloorPlanOptions& options);

// The same, at the best placement within +-search_m and +-search_rad of `world_from_map`
// (grid search in steps of one cell and 0.25 deg), as Sales 2014's best-fit alignment.
MapAgreement BestFitAgreement(const GridMap& map, const World& world, const Eigen::Vector3d& world_from_map,
                              const FloorPlanOptions& options, double search_m, double search_rad);

}  // namespace sim
}  // namespace sarmap
