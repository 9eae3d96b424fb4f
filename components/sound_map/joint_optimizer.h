#pragma once
// Joint optimisation of robot poses, landmarks and sound sources (Su 2017 §4.2, eq. 4.2):
//   x* = argmin_x  sum_ij e_ij' Omega_ij e_ij
// over odometry edges (pose_i^-1 pose_j vs the measured increment), range-bearing landmark
// edges and sound bearing edges (azimuth [, elevation] of a Euclidean source seen from a
// pose through the array mount). Solved by Levenberg-Marquardt in Ceres with
// SPARSE_NORMAL_CHOLESKY (SuiteSparse). The first pose is held fixed (gauge).

#include <Eigen/Core>
#include <vector>

#include "sound_map/simulation.h"
#include "sound_map/sound_geometry.h"

namespace sarmap {
namespace sound_map {

struct JointProblem2d {
  bool three_d = false;
  ArrayMount mount;
  std::vector<Pose2> poses;               // initial guess in, estimate out
  std::vector<Eigen::Vector2d> landmarks; // initial guess in, estimate out
  std::vector<Eigen::Vector3d> sources;   // initial guess in, estimate out (z unused in 2D)
  std::vector<bool> source_observed;      // sources with at least one edge
  struct Odometry {
    int from, to;
    Pose2 delta;
    Eigen::Matrix3d covariance;
  };
  struct LandmarkEdge {
    int pose, landmark;
    Eigen::Vector2d z;
    Eigen::Matrix2d covariance;
  };
  struct SoundEdge {
    int pose, source;
    Eigen::VectorXd z;
    double sigma_rad;
  };
  std::vector<Odometry> odometry;
  std::vector<LandmarkEdge> landmark_edges;
  std::vector<SoundEdge> sound_edges;
  bool use_sound_edges = true;
  // Huber loss on the whitened sound residuals, in sigmas (0: plain least squares). Real
  // logs hold reflections and DOAs pulled by other emitters that pass the gate.
  double sound_huber_sigmas = 0;
};

struct JointReport {
  double solve_seconds = 0;
  int iterations = 0;
  bool usable = false;
  double initial_cost = 0, final_cost = 0;
};

// Builds the problem from a simulation: poses by dead reckoning, landmarks from their first
// observation, sources by least-squares intersection of their bearing rays.
JointProblem2d JointProblemFromSimulation(const Sim2dData& data, bool use_landmarks);

// Least-squares intersection of rays (origin, unit direction); false when the rays are too
// parallel to fix a point (then *point is `fallback_range_m` along the first ray).
bool IntersectRays(const std::vector<Eigen::Vector3d>& origins, const std::vector<Eigen::Vector3d>& dirs,
                   double fallback_range_m, Eigen::Vector3d* point);

// Re-initialises every source by intersecting its rays from the current pose estimates.
void TriangulateSources(JointProblem2d* problem);

JointReport SolveJoint(JointProblem2d* problem, int max_iterations = 100);

// A recorded run as a joint problem (§4.2 on a log, without landmarks): one pose node per
// DOA block at the trajectory's pose of that time (e.g. SLAM's POSE), odometry edges between
// consecutive nodes carrying the trajectory's own increments with
// sigma = floor + per_m * distance; each DOA joins, as a bearing edge, the source of
// `initial_sources` whose predicted bearing from the node is nearest within `gate_chi2`
// (DOAs that fit none are left out). The solution keeps the trajectory's shape where the
// sound does not bend it.
// Defaults for SLAM's POSE, locally accurate (scan-matched): with wheel-odometry-like sigmas
// (1 cm + 5 %/m, 0.5 deg + 2 deg/m) the open-area log's biased DOAs bent the trajectory and
// the sources came out 0.08-0.57 m off; with these, 0.10-0.28 m (sarmap-log sound-map --joint).
struct LogJointOptions {
  double odometry_sigma_floor_m = 0.001;
  double odometry_sigma_m_per_m = 0.005;
  double odometry_sigma_floor_deg = 0.05;
  double odometry_sigma_deg_per_m = 0.2;
  double doa_sigma_floor_deg = 2.0;
  double gate_chi2 = 9.0;
  double huber_sigmas = 2.0;
};
struct LogBearing {
  double azimuth_rad = 0, elevation_rad = 0, sigma_rad = 0;
};
JointProblem2d JointProblemFromLog(const std::vector<Pose2>& poses, const std::vector<std::vector<LogBearing>>& bearings,
                                   const std::vector<Eigen::Vector3d>& initial_sources, const ArrayMount& mount,
                                   bool three_d, const LogJointOptions& options);
// Builds, solves, and associates again against the solved sources until the bearing edges
// stop changing (at most `rounds` solves): a guess half a metre off a source 2 m away misses
// its bearings by 15 deg, outside the gate. *problem holds the last problem and solution.
JointReport SolveJointFromLog(const std::vector<Pose2>& poses, const std::vector<std::vector<LogBearing>>& bearings,
                              const std::vector<Eigen::Vector3d>& initial_sources, const ArrayMount& mount,
                              bool three_d, const LogJointOptions& options, JointProblem2d* problem, int rounds = 5);

}  // namespace sound_map
}  // namespace sarmap
