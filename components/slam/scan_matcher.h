#pragma once
// Scan matching against a probability grid: a brute-force correlative search (local SLAM), a
// branch-and-bound correlative search over a large window (loop closure), and a Ceres
// refinement of either. `points` are in the scan (tracking) frame; poses are grid_from_scan.

#include <array>
#include <cstdint>
#include <vector>

#include "slam/grid.h"

namespace sarmap {
namespace slam {

// Voxel filter: keeps one point per `size_m` cell (the first seen).
PointCloud VoxelFilter(const PointCloud& points, float size_m);
// Largest voxel size <= max_length_m that still leaves `min_points` (Cartographer's adaptive
// voxel filter); points farther than max_range_m are dropped first.
PointCloud AdaptiveVoxelFilter(const PointCloud& points, float max_length_m, int min_points,
                               float max_range_m);

// The angular step at which the farthest point moves by about one cell:
//   step = acos(1 - r^2 / (2 d^2)),  r = resolution, d = max point range.
// Points farther than `max_range_cap_m` do not make the step finer (the Ceres refinement
// recovers the last fraction of a step).
double AngularSearchStep(const PointCloud& points, double resolution_m,
                         double max_range_cap_m = 1e9);

// The points that land, at `pose`, where the grid knows the space around them: the point's
// cell is observed, and so is at least one cell of each pair of opposite neighbours (left and
// right, below and above, both diagonals). Left out are the points beyond what the grid has
// seen and those on its newest edge, a sliver with unknown cells on both sides. Matched, they
// would pull towards the known map, as unknown cells cost what free ones do: a robot driving
// into new space would be held back at every scan, and a corridor seen by a narrow scan would
// come out several per cent short.
PointCloud MatchablePoints(const ProbabilityGrid& grid, const PointCloud& points,
                           const Rigid2d& pose);

// Mean matched probability of the points at `pose` (probabilities at cell centres).
double ScoreAt(const ProbabilityGrid& grid, const PointCloud& points, const Rigid2d& pose);

struct CorrelativeOptions {
  double linear_window_m = 0.1;
  double angular_window_rad = 0.35;
  // Candidate score is score * exp(-(w_t |dt|^2 + w_r dtheta^2)): prefers the prediction
  // among nearly equal candidates.
  double translation_delta_cost_weight = 0.1;
  double rotation_delta_cost_weight = 0.1;
  double step_range_cap_m = 10.0;  // see AngularSearchStep
};

// Exhaustive search around `initial`; returns the best pose and its (unweighted) score.
Rigid2d CorrelativeMatch(const ProbabilityGrid& grid, const PointCloud& points,
                         const Rigid2d& initial, const CorrelativeOptions& options, double* score);

struct CeresMatcherOptions {
  double occupied_space_weight = 1.0;
  double translation_weight = 10.0;
  double rotation_weight = 40.0;
  int max_iterations = 20;
};

// Minimises, over the pose T = (x, y, theta),
//   sum_i (w_o / sqrt(N) * (1 - P(T p_i)))^2 + (w_t |t - t_prior|)^2 + (w_r (theta -
//   theta_prior))^2
// with P bicubically interpolated between cell centres (unknown cells = kMinProbability).
Rigid2d CeresMatch(const ProbabilityGrid& grid, const PointCloud& points, const Rigid2d& prior,
                   const Rigid2d& initial, const CeresMatcherOptions& options);

// The Gauss-Newton information H = J^T J of CeresMatch's map term at `pose` (mean over the
// points, as in CeresMatch), over (x, y, theta) in the grid frame. Its translation block tells
// which directions the match pins: a scan of corridor walls pins the direction across them,
// hardly the one along them. Zero for no points.
Eigen::Matrix3d MapTermHessian(const ProbabilityGrid& grid, const PointCloud& points,
                               const Rigid2d& pose, double occupied_space_weight);

// What the map term of CeresMatch can tell about the heading at `pose`: with J the Jacobian of
// its residuals r_i = w_o / sqrt(N) * (1 - P(T p_i)) with respect to (x, y, theta) and
// H = J^T J (Gauss-Newton information, + w_t^2 on x and y for the translation prior), the
// information on theta once the translation is left free (Schur complement):
//   I_theta = H_tt - H_tx H_xx^-1 H_xt     [1 / rad^2, same units as w_r^2]
// A scan that sees corners is large here; a corridor seen over a narrow field of view, where
// turning the scan can be traded for sliding it, is small.
double RotationInformation(const ProbabilityGrid& grid, const PointCloud& points,
                           const Rigid2d& pose, double occupied_space_weight,
                           double translation_weight);

// The rotation prior weight for a scan with heading information `info`: `base_weight` while
// info <= info_low, `informative_weight` once info >= info_high, log-linear (in both) between.
// informative_weight <= 0 means off: base_weight always.
double AdaptiveRotationWeight(double info, double base_weight, double informative_weight,
                              double info_low, double info_high);

// Max-pooled copies of a grid for branch and bound: level h holds, for cell (x, y), the
// maximum over cells [x, x + 2^h) x [y, y + 2^h), as 0..255 for [kMinProbability,
// kMaxProbability] (unknown = 0). An upper bound of the score of every pose whose offsets lie
// in that window.
class PrecomputationStack {
 public:
  PrecomputationStack(const ProbabilityGrid& grid, int depth);
  int depth() const { return static_cast<int>(levels_.size()); }
  int Value(int level, int x, int y) const {
    x += offset_;
    y += offset_;
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return 0;
    return levels_[level][static_cast<size_t>(y) * width_ + x];
  }
  // Whether (x, y) lies inside the stored levels (Value() is 0 outside).
  bool Contains(int x, int y) const {
    x += offset_;
    y += offset_;
    return x >= 0 && y >= 0 && x < width_ && y < height_;
  }
  size_t MemoryBytes() const { return levels_.size() * static_cast<size_t>(width_) * height_; }
  // Row-major storage of a level: cell (x, y) with Contains() is at Level(l)[Index(x, y)], and
  // Index(x + dx, y + dy) = Index(x, y) + Index(dx, dy) - Index(0, 0).
  const uint8_t* Level(int level) const { return levels_[level].data(); }
  ptrdiff_t Index(int x, int y) const {
    return static_cast<ptrdiff_t>(y + offset_) * width_ + x + offset_;
  }

 private:
  int offset_, width_, height_;
  std::vector<std::vector<uint8_t>> levels_;
};

struct BranchAndBoundOptions {
  double linear_window_m = 7.0;
  double angular_window_rad = 0.52;
  int depth = 7;
  double step_range_cap_m = 15.0;  // see AngularSearchStep
};

// Finds the pose in the window around `initial` whose score is highest and >= min_score
// (branch and bound over the precomputation stack, exact at the finest level). Returns false
// if no candidate reaches min_score.
bool BranchAndBoundMatch(const ProbabilityGrid& grid, const PrecomputationStack& stack,
                         const PointCloud& points, const Rigid2d& initial,
                         const BranchAndBoundOptions& options, double min_score, Rigid2d* pose,
                         double* score);

// Whether `found`, a BranchAndBoundMatch of `points` around `initial`, lies on the boundary of
// the searched window: its outermost row or column of translations, or its outermost angle.
bool OnWindowBoundary(const ProbabilityGrid& grid, const PointCloud& points, const Rigid2d& initial,
                      const BranchAndBoundOptions& options, const Rigid2d& found);

}  // namespace slam
}  // namespace sarmap
