// sarmap-log map-agreement WORLD MAP.yaml: how well a SLAM map (map_server PGM + YAML, as
// sarmap-slam writes with map_output_prefix) agrees with the true floor plan of a simulated
// world: the simulated acceptance of the mapping.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/args.h"
#include "common/grid_geometry.h"
#include "sim/floor_plan.h"
#include "sim/world.h"
#include "slam/map_io.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log map-agreement", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log map-agreement",
        "Compares a SLAM map with the true floor plan of a simulated world (walls, glass, boxes,\n"
        "tables in the scan's height band; cells near people left out): over the cells the map knows,\n"
        "the fraction that agree within a tolerance, for all known cells and for the occupied ones,\n"
        "and what the glass did (glass cells mapped free). The map is placed in the world at the\n"
        "robot's start pose (the SLAM map frame), then at the best fit within a small search, as\n"
        "Sales 2014 did (94.3 % on a real lab).");
    std::string world_path, map_path;
    sarmap::sim::FloorPlanOptions o;
    double search_m = 0.15, search_deg = 2.0;
    parser.AddPositional("WORLD", &world_path, "world file (config/worlds/*.yaml)");
    parser.AddPositional("MAP", &map_path, "map_server YAML of the SLAM map");
    parser.AddFlag("--min-height", &o.min_height_m, "scan height band, bottom (m; config/depth.yaml)");
    parser.AddFlag("--max-height", &o.max_height_m, "scan height band, top (m; config/depth.yaml)");
    parser.AddFlag("--tolerance-cells", &o.tolerance_cells, "a cell agrees when the truth within this many cells does");
    parser.AddFlag("--search", &search_m, "best fit: search +- this many metres");
    parser.AddFlag("--search-deg", &search_deg, "best fit: search +- this many degrees");
    if (!parser.Parse(argc, argv)) return 0;

    const sarmap::sim::World world = sarmap::sim::LoadWorld(world_path);
    const sarmap::slam::OccupancyMap slam_map = sarmap::slam::LoadMapServerMap(map_path);
    sarmap::sim::GridMap map;
    sarmap::common::CopyGridGeometry(slam_map, &map);
    map.cells = slam_map.cells;
    if (world.walls.empty()) throw std::runtime_error("the world '" + world_path + "' has no walls: no floor plan to compare with");

    const Eigen::Vector3d start = world.robot.pose;
    const auto print = [&](const char* how, const sarmap::sim::MapAgreement& a) {
      printf("%s (map placed at x %.3f y %.3f yaw %.2f deg):\n", how, a.world_from_map.x(), a.world_from_map.y(),
             a.world_from_map.z() * 180 / M_PI);
      printf("  agreement %.2f %% of %lld known cells (occupied %.2f %% of %lld, free %.2f %% of %lld)\n",
             100 * a.agreement(), static_cast<long long>(a.known_cells), 100 * a.occupied_agreement(),
             static_cast<long long>(a.occupied_known),
             a.free_known ? 100.0 * a.free_agreeing / a.free_known : 0.0, static_cast<long long>(a.free_known));
      if (a.glass_cells > 0) {
        printf("  glass: %lld of the %lld glass cells the map knows are mapped free (the camera sees through)\n",
               static_cast<long long>(a.glass_cells_seen_free), static_cast<long long>(a.glass_cells));
      }
    };
    print("at the robot's start pose", sarmap::sim::CompareWithFloorPlan(map, world, start, o));
    print("best fit", sarmap::sim::BestFitAgreement(map, world, start, o, search_m, search_deg * M_PI / 180));
    return 0;
  });
}
