#pragma once
// The §4.4.1 experiments (Su 2017): one simulated run mapped by each method, scored against
// the simulation truth. Shared by the unit tests (few Monte Carlo runs) and the
// `sarmap-sound-map-experiments` tool (the full tables).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "sound_map/simulation.h"

namespace sarmap {
namespace sound_map {

enum class Method {
  kEkfOdometry,   // IDP EKF, odometry + sound only (Fig. 4.5)
  kJointOdometry, // joint least squares, odometry + sound only (Fig. 4.5)
  kCiSubmaps,     // localisation EKF (odometry + landmarks) + CI IDP sound map (§4.3)
  kFullEkf,       // one EKF: odometry + landmarks + IDP sources ("full SLAM")
  kJoint,         // joint least squares: odometry + landmarks + sources (§4.2)
};
const char* MethodName(Method m);

struct SourceScore {
  double rms_m = 0;            // over sources that were heard
  double convergence_rate = 0; // fraction of heard sources within converged_error_m
  int num_sources = 0;
  std::vector<double> errors_m;
};
SourceScore ScoreSources(const std::vector<Eigen::Vector3d>& estimates, const std::vector<bool>& heard,
                         const std::vector<Eigen::Vector3d>& truth, bool three_d, double converged_error_m);

struct RunResult {
  SourceScore score;
  double total_seconds = 0;       // wall time of the whole method
  double sound_step_ms_mean = 0;  // EKF methods: mean time of one sound-map step
  double sound_step_ms_max = 0;
  std::vector<Eigen::Vector3d> estimates;
  std::vector<Eigen::Matrix3d> covariances;  // EKF methods
};

struct RunOptions {
  double converged_error_m = 0.5;
  double initial_inverse_depth = 0.2;  // rho_0: 5 m
  double inverse_depth_sigma = 0.2;
  double gate_chi2 = 0;  // 0: no gating (the simulation's association is known)
};

RunResult RunMethod(const Sim2dData& data, Method method, const RunOptions& options = {});

}  // namespace sound_map
}  // namespace sarmap
