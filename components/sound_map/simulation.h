#pragma once
// Simulation harness following Su 2017 §4.4.1 (Table 4.1): a planar robot drives a square
// and, back at the start, continues along +x to close the loop; every 0.2 m step it gets a
// noisy odometry increment, range-bearing observations of point landmarks (Part II) and
// bearing-only observations (azimuth, or azimuth + elevation) of stationary sound sources.
// The thesis gives the step, the noise levels and the trajectory shape; the square size,
// source and landmark layout, hearing range and observation probability are ours
// (documented in README.md).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sound_map/sound_geometry.h"

namespace sarmap {
namespace sound_map {

struct Sim2dConfig {
  double side_m = 10.0;          // square side
  double overshoot_m = 2.0;      // drive on along +x after returning to the start
  double step_m = 0.2;           // distance per odometry step (Table 4.1)
  double odo_sigma_m = 0.001;    // per step, on each of dx, dy (Table 4.1 Part I)
  double odo_sigma_rad = 0.001 * M_PI / 180.0;
  bool three_d = false;          // sound sources at several heights, azimuth + elevation
  double sound_sigma_rad = 10.0 * M_PI / 180.0;  // Table 4.1
  double hearing_range_m = 8.0;
  double heard_probability = 0.5;  // sound is sparse: a source is heard in half the steps
  double source_spacing_m = 5.0;   // one source per this much path, alternating sides
  double source_offset_m = 2.5;    // distance of a source from the path
  bool landmarks = false;          // Part II: range-bearing landmarks
  double landmark_spacing_m = 2.0;
  double landmark_offset_m = 3.0;  // both sides of the path
  double landmark_range_m = 5.0;
  double landmark_sigma_m = 0.01;  // Table 4.1 Part II
  double landmark_sigma_rad = 1.0 * M_PI / 180.0;
  uint64_t seed = 1;
};

struct LandmarkObservation {
  int64_t id;
  Eigen::Vector2d z;  // range_m, bearing_rad
};
struct SoundObservation {
  int64_t source;     // true source index (the DOA tracker's id in the simulation)
  Eigen::VectorXd z;  // azimuth_rad [, elevation_rad] in the array frame
};

struct Sim2dData {
  Sim2dConfig config;
  ArrayMount mount;                       // array at the base origin
  std::vector<Pose2> truth;               // pose k (k = 0 .. K)
  std::vector<Pose2> odometry;            // odometry[k] measures pose k-1 -> k (k >= 1)
  std::vector<std::vector<LandmarkObservation>> landmark_obs;  // at pose k
  std::vector<std::vector<SoundObservation>> sound_obs;        // at pose k
  std::vector<Eigen::Vector3d> sources;   // truth (z = 0 in 2D)
  std::vector<Eigen::Vector2d> landmarks; // truth
  Eigen::Matrix3d odometry_covariance() const;
  double length_m() const;
};

Sim2dData Simulate2d(const Sim2dConfig& config);
// The scenario of Fig. 4.11 (Part II): a square of side_m with range-bearing landmarks, 5 m of
// overshoot and the noisier odometry (0.02 m and 5 deg per step); run r has seed 2000 + r.
Sim2dConfig Fig411Config(double side_m, int run);

}  // namespace sound_map
}  // namespace sarmap
