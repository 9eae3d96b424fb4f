#pragma once
// What one start of a calibration solve reports (shared by Calibrate and
// CalibrateWithArrayPoses; only the .cc files that run Ceres include this).

#include <ceres/ceres.h>
#include <ceres/covariance.h>

#include <algorithm>
#include <cmath>

#include "mic_calibrate/calibration.h"

namespace sarmap {
namespace mic_calibrate {

// normalised_rms = sqrt(2 * cost / residuals): Ceres' cost is half the sum of squares.
inline StartSummary SummariseStart(int start, const ceres::Solver::Summary& summary) {
  StartSummary ss;
  ss.start = start;
  ss.final_cost = summary.final_cost;
  ss.iterations = static_cast<int>(summary.iterations.size()) - 1;
  ss.converged = summary.termination_type == ceres::CONVERGENCE;
  ss.normalised_rms = std::sqrt(2.0 * summary.final_cost / std::max(1, summary.num_residuals));
  ss.num_residuals = summary.num_residuals;
  ss.num_parameters = summary.num_effective_parameters;
  return ss;
}

// Marginal covariances at the solution: sparse QR in SuiteSparse, which also copes with the
// rank-deficient directions that a fixed gauge leaves.
inline ceres::Covariance::Options CovarianceOptions(int num_threads) {
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::SPARSE_QR;
  options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  options.num_threads = num_threads;
  options.min_reciprocal_condition_number = 1e-14;
  return options;
}

}  // namespace mic_calibrate
}  // namespace sarmap
