#pragma once
// Loop-closure consistency gate: a loop closure must agree with what the pose graph already
// knows, within the drift that local SLAM can have built up along the path between the two
// ends of the closure.
//
// Drift model (random walk, per step between consecutive nodes k -> k+1 of local SLAM's chain,
// d_k metres driven, a_k radians turned): a zero-mean perturbation xi_k of node k+1's pose in
// its own frame with covariance
//   Q_k = diag(s_t^2 d_k,  s_t^2 d_k,  s_r^2 a_k + s_rm^2 d_k)
// (s_t: translation drift per sqrt(m), s_r: heading drift per sqrt(rad) turned, s_rm: heading
// drift per sqrt(m) driven). Moved into the local frame (left perturbation, Ad(T) = [R, v; 0, 1],
// v = (y, -x)), step k contributes M_k = Ad(T_{k+1}) Q_k Ad(T_{k+1})^T, and with node a held,
// node b's pose (a < b or a > b) varies by a left perturbation eta with covariance
//   S(a, b) = | P_b - P_a |,  P_m = sum_{k < m} M_k   (prefix sums, one per node).
// Its (x, y, yaw) in the local frame's axes then has covariance B S B^T with
// B = [1 0 -y_b; 0 1 x_b; 0 0 1]: a heading error swings node b about the point where it arose
// (the lever arm), so a robot that only turned on the spot accumulates heading but no position
// uncertainty, and one that drove 100 m accumulates both.

#include <Eigen/Core>
#include <vector>

#include "common/transform.h"

namespace sarmap {
namespace slam {

using common::Rigid2d;

struct DriftModel {
  double translation_m_per_sqrt_m = 0.1;    // s_t
  double rotation_rad_per_sqrt_rad = 0.02;  // s_r
  double rotation_rad_per_sqrt_m = 0.0087;  // s_rm
};

// Prefix sums of the drift model over the chain of node poses in local SLAM's frame.
class ChainDrift {
 public:
  explicit ChainDrift(const DriftModel& model = DriftModel()) : model_(model) {}
  void Clear() {
    poses_.clear();
    prefix_.clear();
  }
  // Appends the next node's local pose.
  void Add(const Rigid2d& local_pose);
  int size() const { return static_cast<int>(poses_.size()); }
  const Rigid2d& pose(int i) const { return poses_[static_cast<size_t>(i)]; }
  // Covariance of node b's (x, y, yaw), in the local frame's axes, while node a is held fixed.
  Eigen::Matrix3d RelativeCovariance(int a, int b) const;
  size_t MemoryBytes() const {
    return poses_.capacity() * sizeof(Rigid2d) + prefix_.capacity() * sizeof(Eigen::Matrix3d);
  }

 private:
  DriftModel model_;
  std::vector<Rigid2d> poses_;
  std::vector<Eigen::Matrix3d> prefix_;  // P_m
};

// Squared Mahalanobis distance of a loop closure: `measured` and `predicted` are both
// submap_from_node (the closure's match and the graph's current estimate), `covariance` the
// predicted pose's (x, y, yaw) covariance in the submap's axes (drift plus match noise).
// The error is (t_measured - t_predicted, wrap(yaw_measured - yaw_predicted)).
double LoopClosureMahalanobisSquared(const Rigid2d& predicted, const Rigid2d& measured,
                                     const Eigen::Matrix3d& covariance);

// The gate: the closure of node `node` in a submap whose node `reference` drew the matched
// part agrees with the graph when its squared Mahalanobis distance, with the chain's drift
// between the two nodes plus two scan-to-submap matches' noise (the closure's and the
// reference's own), is at most max_chi2. `d2`, when given, receives the distance.
bool LoopClosureConsistent(const ChainDrift& chain, int reference, int node,
                           const Rigid2d& predicted, const Rigid2d& measured, double match_sigma_m,
                           double match_sigma_rad, double max_chi2, double* d2 = nullptr);

}  // namespace slam
}  // namespace sarmap
