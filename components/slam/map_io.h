#pragma once
// ROS map_server maps: a PGM image (trinary: occupied 0, free 254, unknown 205; top row is the
// highest y) and a YAML file (image, resolution, origin, negate, occupied_thresh, free_thresh).

#include <string>

#include "slam/slam.h"

namespace sarmap {
namespace slam {

// Writes PREFIX.pgm and PREFIX.yaml (each via temp + rename).
void SaveMapServerMap(const OccupancyMap& map, const std::string& prefix);
// Reads a map_server YAML + PGM (P5, 8 bit) into an occupancy map (0 / 100 / -1 by the
// thresholds). Throws std::runtime_error on errors.
OccupancyMap LoadMapServerMap(const std::string& yaml_path);

}  // namespace slam
}  // namespace sarmap
