#pragma once
// The pose graph: scan nodes and submaps with global poses, and constraints between them.
// Optimised with Ceres (SPARSE_NORMAL_CHOLESKY on SuiteSparse), a Huber loss on loop closures.
//
// A constraint says "node n seen from submap s (or node m) is at z = (z_t, z_theta)"; with
// global poses (t_s, theta_s) and (t_n, theta_n) its residual is
//   r_t     = w_t * S^(1/2) ( R(theta_s)^T (t_n - t_s) - z_t )
//   r_theta = w_r * wrap(theta_n - theta_s - z_theta)
// S (`translation_shape`, in the frame of s) is the identity unless the constraint's match can
// tell some directions better than others (a scan of one wall: across it, not along it).
// Costs are 1/2 |r|^2 (or the Huber loss of it for loop closures).

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/transform.h"

namespace sarmap {
namespace slam {

using common::Rigid2d;

struct Constraint {
  // TRIMMED_CHAIN ties the nodes either side of trimmed ones: the local chain of `steps`
  // consecutive-node constraints it replaces, as springs in series (weight / sqrt(steps)).
  enum Kind { INTRA_SUBMAP = 0, LOOP_CLOSURE = 1, ODOMETRY = 2, LOCAL_SLAM = 3, TRIMMED_CHAIN = 4 };
  Kind kind;
  // For INTRA_SUBMAP / LOOP_CLOSURE: from = submap id, to = node id. For ODOMETRY /
  // LOCAL_SLAM / TRIMMED_CHAIN: from = node id, to = a later node id.
  int from, to;
  Rigid2d relative;  // from_frame_from_to_frame
  double translation_weight, rotation_weight;
  double score = 0;  // loop closure match score
  // Symmetric, positive semi-definite, largest eigenvalue 1: how well the match tells each
  // direction of the translation, relative to its best one (TranslationShape).
  Eigen::Matrix2d translation_shape = Eigen::Matrix2d::Identity();
  int steps = 1;  // TRIMMED_CHAIN: consecutive-node steps replaced
  bool submap_to_node() const { return kind == INTRA_SUBMAP || kind == LOOP_CLOSURE; }
};

// The shape of a match's translation information H (2x2, Gauss-Newton J^T J of the match in the
// constraint's frame): H / lambda_max(H). A match along a wall gets ~0 along the wall and 1
// across it; a match that sees corners stays near the identity. False when H tells nothing
// (lambda_max not positive, or not finite).
bool TranslationShape(const Eigen::Matrix2d& information, Eigen::Matrix2d* shape);

struct PoseGraphOptions {
  int max_iterations = 50;
  double huber_scale = 10.0;
};

// What NodeCovariance assumes about each constraint's noise. The optimiser's weights are tuning
// weights (a local-matching weight of 1e5 says "1e-5 m"), so the covariance they imply is ~1e5 too
// tight in variance. Here each kind may state the standard deviation of one constraint instead:
// the covariance's information for it is diag(1/sigma_t^2, 1/sigma_t^2, 1/sigma_r^2). 0 keeps the
// optimiser's weight (information w^2). A TRIMMED_CHAIN of n steps has local_slam's sigma
// times sqrt(n).
struct ConstraintNoise {
  double translation_sigma_m = 0;
  double rotation_sigma_rad = 0;
};
struct CovarianceModel {
  ConstraintNoise intra_submap, loop_closure, odometry, local_slam;
  const ConstraintNoise& For(int kind) const;
  // The (translation, rotation) square-root information this model gives constraint c.
  std::pair<double, double> Weights(const Constraint& c) const;
};

struct OptimisationSummary {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  double seconds = 0;
};

// Optimises `node_poses` and `submap_poses` (indexed by id) in place. Submap 0 stays fixed.
// Poses no constraint names (trimmed) are left as they are.
OptimisationSummary OptimisePoseGraph(const std::vector<Constraint>& constraints,
                                      std::vector<Rigid2d>* node_poses,
                                      std::vector<Rigid2d>* submap_poses,
                                      const PoseGraphOptions& options);

// Joint covariance of the listed nodes' (x, y, yaw) at the current poses (3k x 3k): blocks of
// the inverse of the whole graph's Gauss-Newton information J^T J (sparse Cholesky, submap 0
// fixed). False when the covariance cannot be computed (rank deficient).
bool NodeCovariance(const std::vector<Constraint>& constraints,
                    const std::vector<Rigid2d>& node_poses,
                    const std::vector<Rigid2d>& submap_poses, const std::vector<int>& node_ids,
                    Eigen::MatrixXd* covariance, const PoseGraphOptions& options,
                    const CovarianceModel& model = CovarianceModel());

}  // namespace slam
}  // namespace sarmap
