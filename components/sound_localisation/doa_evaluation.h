#pragma once
// Offline DOA accuracy on a labelled multichannel recording: runs the streaming localiser
// over the file and compares every block's strongest direction (and a whole-file estimate)
// with the true direction.

#include <string>
#include <vector>

#include "sound_localisation/localiser.h"

namespace sarmap {
namespace sound {

struct DoaFileResult {
  std::string file, method;
  int blocks = 0;                   // blocks with an estimate
  double median_azimuth_error_deg = NAN, median_elevation_error_deg = NAN;
  double mean_azimuth_error_deg = NAN;
  double whole_azimuth_deg = NAN, whole_elevation_deg = NAN;  // one estimate from all active frames
  std::vector<Direction> block_estimates;
};

// truth: azimuth/elevation (1-D arrays: angle to the axis in azimuth_rad).
DoaFileResult EvaluateDoaFile(const std::string& path, const ArrayGeometry& geometry,
                              const LocaliserOptions& options, const Direction& truth);
double Median(std::vector<double> v);

}  // namespace sound
}  // namespace sarmap
