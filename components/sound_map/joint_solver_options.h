#pragma once
// The Ceres solver options of the sound maps' joint refinements of sources and poses: the
// ch. 4 JointOptimizer and the ch. 5 linear-array mappers (handheld_sound_map).

#include <ceres/ceres.h>

namespace sarmap {
namespace sound_map {

// Sparse normal equations (SuiteSparse), a Levenberg-Marquardt trust region, one thread, no log.
inline ceres::Solver::Options JointSolverOptions(int max_iterations) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

}  // namespace sound_map
}  // namespace sarmap
