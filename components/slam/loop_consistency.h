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
#include <map>

#include "common/transform.h"

namespace sarmap {
namespace slam {

using common::Rigid2d;

struct DriftModel {
  double translation_m_per_sqrt_m = 0.1;    // s_t
  double rotation_rad_per_sqrt_rad = 0.02;  // s_r
  double rotation_rad_per_sqrt_m = 0.0087;  // s_rm
};

// Prefix sums of the drift model over the chain of node poses in local SLAM's frame. Nodes
// that can no longer end a loop closure (trimmed) are released: P_m is a running sum, so the
// nodes kept stay exact and the chain holds only as many entries as there are live nodes.
class ChainDrift {
 public:
  explicit ChainDrift(const DriftModel& model = DriftModel()) : model_(model) {}
  void Clear() {
    entries_.clear();
    size_ = 0;
  }
  // Appends the next node's local pose (node id size()).
  void Add(const Rigid2d& local_pose);
  // Forgets node i (no-op if it was not added or is already released).
  void Release(int i) { entries_.erase(i); }
  int size() const { return size_; }  // nodes added, released or not
  bool Holds(int i) const { return entries_.count(i) > 0; }
  const Rigid2d& pose(int i) const { return entries_.at(i).pose; }
  // Covariance of node b's (x, y, yaw), in the local frame's axes, while node a is held fixed.
  // A released end has no drift bound: every element is +infinity (no closure passes).
  Eigen::Matrix3d RelativeCovariance(int a, int b) const;
  size_t MemoryBytes() const {
    return entries_.size() * (sizeof(Entry) + sizeof(int) + 4 * sizeof(void*));  // map nodes
  }

 private:
  struct Entry {
    Rigid2d pose;
    Eigen::Matrix3d prefix;  // P_m
  };
  DriftModel model_;
  std::map<int, Entry> entries_;
  int size_ = 0;
  Entry last_;  // the last node added (its successor's increment starts from it)
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
