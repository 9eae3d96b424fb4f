#include "sim/floor_plan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace sarmap {
namespace sim {
namespace {

// A 4 x 3 m room with a box and a glass pane across the middle of the east half.
World Room() {
  World w;
  const auto wall = [&](Eigen::Vector2d a, Eigen::Vector2d b, bool glass = false) {
    Wall x;
    x.from = a;
    x.to = b;
    x.glass = glass;
    w.walls.push_back(x);
  };
  wall({0, 0}, {4, 0});
  wall({4, 0}, {4, 3});
  wall({4, 3}, {0, 3});
  wall({0, 3}, {0, 0});
  wall({3, 0}, {3, 3}, true);
  Box b;
  b.centre = {1, 2};
  b.size_m = {0.4, 0.4, 0.8};
  w.boxes.push_back(b);
  Box shelf;  // above the scan band: not in the floor plan
  shelf.centre = {2, 1};
  shelf.base_m = 1.5;
  shelf.size_m = {0.4, 0.4, 0.3};
  w.boxes.push_back(shelf);
  return w;
}

// The floor plan as a SLAM map would show it, in a frame `world_from_map` = (x, y, yaw), glass
// mapped free (the camera sees through it).
GridMap MapOf(const World& world, const Eigen::Vector3d& world_from_map) {
  FloorPlanOptions o;
  World no_glass = world;
  no_glass.walls.erase(std::remove_if(no_glass.walls.begin(), no_glass.walls.end(), [](const Wall& w) { return w.glass; }),
                       no_glass.walls.end());
  // Rasterise in the world, then resample into the map frame.
  const GridMap truth = RasteriseFloorPlan(no_glass, o, 0.05, Eigen::Vector2d(-1, -1), 120, 100);
  GridMap map;
  map.resolution_m = 0.05;
  map.width = 120;
  map.height = 100;
  map.origin_x_m = -3;
  map.origin_y_m = -2;
  map.cells.assign(map.width * map.height, -1);
  const double c = std::cos(world_from_map.z()), s = std::sin(world_from_map.z());
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const double px = map.origin_x_m + (x + 0.5) * 0.05, py = map.origin_y_m + (y + 0.5) * 0.05;
      const double wx = world_from_map.x() + c * px - s * py, wy = world_from_map.y() + s * px + c * py;
      if (wx < 0 || wy < 0 || wx > 4 || wy > 3) continue;  // only the inside is known
      const int tx = static_cast<int>(std::floor((wx + 1) / 0.05)), ty = static_cast<int>(std::floor((wy + 1) / 0.05));
      map.cells[y * map.width + x] = truth.cells[ty * truth.width + tx];
    }
  }
  return map;
}

TEST(FloorPlanTest, RasterisesWallsBoxesAndOnlyWhatIsInTheScanBand) {
  const World w = Room();
  const GridMap g = RasteriseFloorPlan(w, FloorPlanOptions(), 0.05, Eigen::Vector2d(0, 0), 80, 60);
  const auto at = [&](double x, double y) { return g.cells[static_cast<int>(y / 0.05) * g.width + static_cast<int>(x / 0.05)]; };
  EXPECT_EQ(at(0.01, 1.5), 100);  // west wall
  EXPECT_EQ(at(1.0, 2.0), 100);   // box
  EXPECT_EQ(at(2.0, 1.0), 0);     // shelf above the band
  EXPECT_EQ(at(3.0, 1.5), 100);   // glass is part of the floor plan
  EXPECT_EQ(at(2.0, 2.0), 0);
}

TEST(FloorPlanTest, AMapOfTheFloorPlanAgreesAndAMisplacedOneDoesNot) {
  const World w = Room();
  const Eigen::Vector3d world_from_map(1.0, 0.5, 0.3);
  const GridMap map = MapOf(w, world_from_map);
  const MapAgreement right = CompareWithFloorPlan(map, w, world_from_map, FloorPlanOptions());
  EXPECT_GT(right.known_cells, 3000);
  EXPECT_GT(right.occupied_known, 200);
  // Everything agrees except glass cells, which the map shows free (those more than a cell
  // from free truth).
  EXPECT_EQ(right.occupied_agreement(), 1.0);
  EXPECT_GT(right.glass_cells_seen_free, 40);
  EXPECT_GT(right.known_cells, right.agreeing_cells);
  EXPECT_LE(right.known_cells - right.agreeing_cells, right.glass_cells_seen_free);
  EXPECT_GT(right.agreement(), 0.98);
  // 20 cm and 3 degrees off: walls no longer agree.
  const MapAgreement wrong = CompareWithFloorPlan(map, w, world_from_map + Eigen::Vector3d(0.2, 0, 0.05), FloorPlanOptions());
  EXPECT_LT(wrong.agreement(), right.agreement() - 0.03);
  EXPECT_LT(wrong.occupied_agreement(), 0.7);
  // The best fit within 25 cm / 4 degrees finds the placement back.
  const MapAgreement best =
      BestFitAgreement(map, w, world_from_map + Eigen::Vector3d(0.1, -0.05, 0.02), FloorPlanOptions(), 0.15, 2 * M_PI / 180);
  EXPECT_NEAR(best.agreement(), right.agreement(), 0.01);
}

// Two 3.9 x 2.9 m rooms (inside the walls) side by side, joined by a door of `door_m` in the
// shared wall; the robot starts in the west room.
World TwoRooms(double door_m) {
  World w;
  const auto wall = [&](Eigen::Vector2d a, Eigen::Vector2d b) {
    Wall x;
    x.from = a;
    x.to = b;
    w.walls.push_back(x);
  };
  wall({0, 0}, {8, 0});
  wall({8, 0}, {8, 3});
  wall({8, 3}, {0, 3});
  wall({0, 3}, {0, 0});
  wall({4, 0}, {4, 1.0});
  wall({4, 1.0 + door_m}, {4, 3});
  w.robot.pose = {2, 1.5, 0};
  return w;
}

TEST(ReachableFloorTest, ANarrowDoorKeepsTheRobotInOneRoomAWideOneLetsItThrough) {
  // The gap between the door's wall ends must exceed the robot's diameter plus the walls'
  // half-thicknesses: 2 * 0.25 + 2 * 0.05 = 0.6 m.
  const GridMap narrow = ReachableFloor(TwoRooms(0.5), 0.25, 0.05);
  EXPECT_EQ(CellAt(narrow, {2, 1.5}), 0);
  EXPECT_EQ(CellAt(narrow, {6, 1.5}), -1);
  EXPECT_EQ(CellAt(narrow, {4, 0.5}), 100);   // the wall
  EXPECT_EQ(CellAt(narrow, {-1, 1.5}), -1);   // outside the grid
  EXPECT_EQ(CellAt(narrow, {0.17, 0.17}), 0);  // the body reaches into the corners...
  EXPECT_EQ(CellAt(narrow, {0.08, 0.08}), -1);  // ...but not right into them
  // One room: 3.9 x 2.9 = 11.31 m^2 less r^2 (1 - pi/4) = 0.013 m^2 per corner, plus the body
  // reaching into the door.
  const double one = FloorArea(narrow);
  std::printf("narrow door: %.3f m^2\n", one);
  EXPECT_NEAR(one, 11.31, 0.25);
  const GridMap wide = ReachableFloor(TwoRooms(0.9), 0.25, 0.05);
  EXPECT_EQ(CellAt(wide, {6, 1.5}), 0);
  const double two = FloorArea(wide);
  std::printf("wide door: %.3f m^2\n", two);
  EXPECT_NEAR(two, 2 * 11.31, 0.4);
}

TEST(ReachableFloorTest, BoxesAreFootprintTablesOnlyTheirLegs) {
  World w = TwoRooms(0.9);
  Box cabinet;
  cabinet.centre = {6, 1.5};
  cabinet.size_m = {1.0, 1.0, 1.8};
  w.boxes.push_back(cabinet);
  Table table;
  table.centre = {2, 1.5};
  table.size_m = {1.6, 1.0};
  w.tables.push_back(table);
  w.robot.pose = {1, 1, 0};
  const GridMap g = ReachableFloor(w, 0.25, 0.05);
  EXPECT_EQ(CellAt(g, {6, 1.5}), 100);
  EXPECT_EQ(CellAt(g, {2, 1.5}), 0);  // under the table, between its legs
  EXPECT_EQ(CellAt(g, {2 + 0.8 - 0.05, 1.5 + 0.5 - 0.05}), 100);  // a leg
  EXPECT_NEAR(FloorArea(g), 2 * 11.31 - 1.0, 0.45);
  // A person lying in the door blocks it only when people count as obstacles.
  Person p;
  p.position = {4, 1.45};
  p.posture = Posture::kLying;
  w.people.push_back(p);
  EXPECT_EQ(CellAt(ReachableFloor(w, 0.25, 0.05), {6, 0.5}), 0);
  EXPECT_EQ(CellAt(ReachableFloor(w, 0.25, 0.05, true), {6, 0.5}), -1);
}

TEST(ReachableFloorTest, NothingIsReachableFromAStartInsideAnObstacle) {
  World w = TwoRooms(0.9);
  w.robot.pose = {4, 0.5, 0};
  EXPECT_EQ(FloorArea(ReachableFloor(w, 0.25, 0.05)), 0.0);
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
