#pragma once
// The mission as a RoboCup-Rescue-style GeoTIFF (as hector_geotiff draws it): the occupancy
// grid at one pixel per cell (free (< 50) white, obstacles (>= 65) dark blue, between a grey
// blue, unknown a 1 m checkerboard of two light greys), 1 m grid lines, the robot's path
// (orange), the start pose (green arrow), the people found (filled discs coloured by how they
// were found, numbered, with 3-sigma uncertainty ellipses) and the sound sources (converged:
// filled blue squares with 3-sigma ellipses; initialising: hollow squares). People and
// sources the report lists as unconverged or outside the map are not drawn.
//
// Georeference: pixel size = the map's resolution; the geotransform maps pixel corners to the
// map frame in metres (x east, y north, row 0 at the top = the grid's last row), rotated by the
// grid's origin_yaw_rad; the CRS is a local engineering one named "sarmap map frame".

#include <array>
#include <string>

#include "log-tools/mission_report.h"

namespace sarmap {
namespace logtools {

// RGB colours of what the GeoTIFF draws.
struct GeoTiffColours {
  static constexpr std::array<uint8_t, 3> kFree{255, 255, 255};
  static constexpr std::array<uint8_t, 3> kOccupied{0, 40, 120};
  static constexpr std::array<uint8_t, 3> kUnknownA{226, 226, 227};
  static constexpr std::array<uint8_t, 3> kUnknownB{237, 237, 238};
  static constexpr std::array<uint8_t, 3> kGrid{190, 205, 230};
  static constexpr std::array<uint8_t, 3> kPath{255, 140, 0};
  static constexpr std::array<uint8_t, 3> kStart{0, 170, 0};
  static constexpr std::array<uint8_t, 3> kSeen{220, 0, 0};
  static constexpr std::array<uint8_t, 3> kHeard{200, 0, 200};
  static constexpr std::array<uint8_t, 3> kSeenAndHeard{255, 200, 0};
  static constexpr std::array<uint8_t, 3> kSoundSource{0, 110, 255};
};

// The colour a person is drawn in, by how they were found.
std::array<uint8_t, 3> PersonColour(int cues);

// The GDAL geotransform of the map (pixel (col, row) corner -> map frame):
// x = g[0] + col g[1] + row g[2], y = g[3] + col g[4] + row g[5].
std::array<double, 6> MapGeoTransform(const sarmap::occupancy_grid_t& map);

// Writes the GeoTIFF; throws std::runtime_error without a map or when the file cannot be written.
void WriteGeoTiff(const MissionData& data, const MissionSummary& summary, const std::string& path);

}  // namespace logtools
}  // namespace sarmap
