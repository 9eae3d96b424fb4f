#include "slam/scan_matcher.h"

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <unordered_set>

namespace sarmap {
namespace slam {

PointCloud VoxelFilter(const PointCloud& points, float size_m) {
  PointCloud out;
  out.reserve(points.size());
  std::unordered_set<uint64_t> seen;
  seen.reserve(points.size() * 2);
  const float inv = 1.f / size_m;
  for (const auto& p : points) {
    const int64_t x = static_cast<int64_t>(std::floor(p.x() * inv));
    const int64_t y = static_cast<int64_t>(std::floor(p.y() * inv));
    const uint64_t key =
        (static_cast<uint64_t>(x) << 32) ^ (static_cast<uint64_t>(y) & 0xffffffffu);
    if (seen.insert(key).second) out.push_back(p);
  }
  return out;
}

PointCloud AdaptiveVoxelFilter(const PointCloud& points, float max_length_m, int min_points,
                               float max_range_m) {
  PointCloud in;
  in.reserve(points.size());
  for (const auto& p : points) {
    if (p.norm() <= max_range_m) in.push_back(p);
  }
  if (static_cast<int>(in.size()) <= min_points) return in;
  PointCloud result = VoxelFilter(in, max_length_m);
  if (static_cast<int>(result.size()) >= min_points) return result;
  // Binary search for the largest length that keeps enough points.
  float high = max_length_m, low = max_length_m;
  for (int i = 0; i < 20; ++i) {
    low /= 2;
    result = VoxelFilter(in, low);
    if (static_cast<int>(result.size()) >= min_points) break;
  }
  for (int i = 0; i < 6 && high / low > 1.1f; ++i) {
    const float mid = 0.5f * (low + high);
    PointCloud candidate = VoxelFilter(in, mid);
    if (static_cast<int>(candidate.size()) >= min_points) {
      low = mid;
      result.swap(candidate);
    } else {
      high = mid;
    }
  }
  return result;
}

double AngularSearchStep(const PointCloud& points, double resolution_m, double max_range_cap_m) {
  double max_range = 3 * resolution_m;
  for (const auto& p : points) max_range = std::max<double>(max_range, p.norm());
  max_range = std::max(3 * resolution_m, std::min(max_range, max_range_cap_m));
  return std::acos(1. - resolution_m * resolution_m / (2. * max_range * max_range));
}

double ScoreAt(const ProbabilityGrid& grid, const PointCloud& points, const Rigid2d& pose) {
  if (points.empty()) return 0;
  double sum = 0;
  const Eigen::Matrix2f r = pose.rotation().toRotationMatrix().cast<float>();
  const Eigen::Vector2f t = pose.translation().cast<float>();
  for (const auto& p : points) {
    const Eigen::Array2i c = grid.CellIndex(r * p + t);
    sum += grid.Probability(c.x(), c.y());
  }
  return sum / points.size();
}

namespace {

// Points rotated by `yaw` and translated by `t`, as cell indices of `grid`.
void DiscretizeScan(const ProbabilityGrid& grid, const PointCloud& points, double yaw,
                    const Eigen::Vector2d& t, std::vector<Eigen::Array2i>* cells) {
  cells->clear();
  const Eigen::Matrix2f r = Eigen::Rotation2Df(static_cast<float>(yaw)).toRotationMatrix();
  const Eigen::Vector2f tf = t.cast<float>();
  for (const auto& p : points) cells->push_back(grid.CellIndex(r * p + tf));
}

// A search window in the steps it is searched in: angles initial + k * angle_step for
// |k| <= num_angles, translations initial + (dx, dy) * resolution for |dx|, |dy| <= cells.
struct DiscreteWindow {
  double angle_step;
  int num_angles;
  int cells;
};

DiscreteWindow Discretize(const PointCloud& points, double resolution_m, double linear_window_m,
                          double angular_window_rad, double step_range_cap_m) {
  DiscreteWindow d;
  d.angle_step = AngularSearchStep(points, resolution_m, step_range_cap_m);
  d.num_angles = static_cast<int>(std::ceil(angular_window_rad / d.angle_step));
  d.cells = static_cast<int>(std::ceil(linear_window_m / resolution_m));
  return d;
}

}  // namespace

Rigid2d CorrelativeMatch(const ProbabilityGrid& grid, const PointCloud& points,
                         const Rigid2d& initial, const CorrelativeOptions& options, double* score) {
  if (points.empty()) {
    if (score) *score = 0;
    return initial;
  }
  const double res = grid.resolution();
  const DiscreteWindow window = Discretize(points, res, options.linear_window_m,
                                           options.angular_window_rad, options.step_range_cap_m);
  const double angle_step = window.angle_step;
  const int num_angles = window.num_angles;
  const int w = window.cells;
  const int side = 2 * w + 1;
  std::vector<Eigen::Array2i> cells;
  std::vector<float> sums(static_cast<size_t>(side) * side);
  double best = -1, best_raw = 0;
  Rigid2d best_pose = initial;
  const float inv_n = 1.f / points.size();
  // nullptr for a finished grid (localisation in a saved map): read cell by cell.
  const float* grid_cells = grid.LiveCells();
  const int grid_w = grid.width(), grid_h = grid.height();
  for (int k = -num_angles; k <= num_angles; ++k) {
    const double dtheta = k * angle_step;
    DiscretizeScan(grid, points, initial.yaw_rad() + dtheta, initial.translation(), &cells);
    std::fill(sums.begin(), sums.end(), 0.f);
    for (const auto& c : cells) {
      const bool columns_inside = grid_cells && c.x() - w >= 0 && c.x() + w < grid_w;
      for (int dy = -w; dy <= w; ++dy) {
        float* row = &sums[static_cast<size_t>(dy + w) * side];
        const int y = c.y() + dy;
        if (columns_inside && y >= 0 && y < grid_h) {
          // The window row lies inside the grid: read it directly (as Probability() does).
          const float* in = &grid_cells[static_cast<size_t>(y) * grid_w + c.x() - w];
          for (int i = 0; i < side; ++i) row[i] += in[i] == 0.f ? kMinProbability : in[i];
        } else {
          for (int dx = -w; dx <= w; ++dx) row[dx + w] += grid.Probability(c.x() + dx, y);
        }
      }
    }
    const double rot_cost = options.rotation_delta_cost_weight * dtheta * dtheta;
    for (int dy = -w; dy <= w; ++dy) {
      for (int dx = -w; dx <= w; ++dx) {
        const double raw = sums[static_cast<size_t>(dy + w) * side + dx + w] * inv_n;
        const double d2 = (dx * dx + dy * dy) * res * res;
        const double s = raw * std::exp(-(options.translation_delta_cost_weight * d2 + rot_cost));
        if (s > best) {
          best = s;
          best_raw = raw;
          best_pose = Rigid2d(initial.translation() + Eigen::Vector2d(dx * res, dy * res),
                              initial.yaw_rad() + dtheta);
        }
      }
    }
  }
  if (score) *score = best_raw;
  return best_pose;
}

PointCloud MatchablePoints(const ProbabilityGrid& grid, const PointCloud& points,
                           const Rigid2d& pose) {
  const auto known = [&grid](const Eigen::Array2i& cell) { return grid.Raw(cell) != 0.f; };
  // Half of the 8-neighbourhood: each offset stands for itself and its opposite.
  static const Eigen::Array2i kPairs[4] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
  PointCloud kept;
  kept.reserve(points.size());
  for (const Eigen::Vector2f& p : points) {
    const Eigen::Array2i cell = grid.CellIndex((pose * p.cast<double>()).cast<float>());
    bool keep = known(cell);
    for (int i = 0; keep && i < 4; ++i) keep = known(cell + kPairs[i]) || known(cell - kPairs[i]);
    if (keep) kept.push_back(p);
  }
  return kept;
}

namespace {

// The grid as a function sampled at cell centres, for ceres::BiCubicInterpolator: the value is
// the "correspondence cost" 1 - P, with unknown and outside cells at the maximum cost.
class GridAdapter {
 public:
  enum { DATA_DIMENSION = 1 };
  explicit GridAdapter(const ProbabilityGrid& grid) : grid_(grid) {}
  void GetValue(int row, int col, double* f) const { *f = 1.0 - grid_.Probability(col, row); }

 private:
  const ProbabilityGrid& grid_;
};

class OccupiedSpaceCost {
 public:
  OccupiedSpaceCost(double scale, const PointCloud& points, const ProbabilityGrid& grid)
      : scale_(scale), points_(points), grid_(grid), adapter_(grid), interpolator_(adapter_) {}

  template <typename T>
  bool operator()(const T* const pose, T* residual) const {
    const T c = ceres::cos(pose[2]), s = ceres::sin(pose[2]);
    const double inv_res = 1.0 / grid_.resolution();
    const double cx = grid_.corner().x(), cy = grid_.corner().y();
    for (size_t i = 0; i < points_.size(); ++i) {
      const T x = c * T(points_[i].x()) - s * T(points_[i].y()) + pose[0];
      const T y = s * T(points_[i].x()) + c * T(points_[i].y()) + pose[1];
      // Cell centres are at integer sample positions.
      const T col = (x - cx) * inv_res - 0.5;
      const T row = (y - cy) * inv_res - 0.5;
      interpolator_.Evaluate(row, col, &residual[i]);
      residual[i] = scale_ * residual[i];
    }
    return true;
  }

 private:
  double scale_;
  const PointCloud& points_;
  const ProbabilityGrid& grid_;
  GridAdapter adapter_;
  ceres::BiCubicInterpolator<GridAdapter> interpolator_;
};

struct TranslationDeltaCost {
  double weight, x, y;
  template <typename T>
  bool operator()(const T* const pose, T* residual) const {
    residual[0] = weight * (pose[0] - x);
    residual[1] = weight * (pose[1] - y);
    return true;
  }
};

struct RotationDeltaCost {
  double weight, theta;
  template <typename T>
  bool operator()(const T* const pose, T* residual) const {
    residual[0] = weight * (pose[2] - theta);
    return true;
  }
};

}  // namespace

Rigid2d CeresMatch(const ProbabilityGrid& grid, const PointCloud& points, const Rigid2d& prior,
                   const Rigid2d& initial, const CeresMatcherOptions& options) {
  if (points.empty()) return initial;
  // Unwrap the initial yaw next to the prior's so the rotation residual is small.
  double pose[3] = {
      initial.translation().x(), initial.translation().y(),
      prior.yaw_rad() + std::remainder(initial.yaw_rad() - prior.yaw_rad(), 2 * M_PI)};
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<OccupiedSpaceCost, ceres::DYNAMIC, 3>(
          new OccupiedSpaceCost(options.occupied_space_weight / std::sqrt(double(points.size())),
                                points, grid),
          static_cast<int>(points.size())),
      nullptr, pose);
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<TranslationDeltaCost, 2, 3>(new TranslationDeltaCost{
          options.translation_weight, prior.translation().x(), prior.translation().y()}),
      nullptr, pose);
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RotationDeltaCost, 1, 3>(
                               new RotationDeltaCost{options.rotation_weight, prior.yaw_rad()}),
                           nullptr, pose);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  return Rigid2d(pose[0], pose[1], pose[2]);
}

Eigen::Matrix3d MapTermHessian(const ProbabilityGrid& grid, const PointCloud& points,
                               const Rigid2d& pose, double occupied_space_weight) {
  if (points.empty()) return Eigen::Matrix3d::Zero();
  const int n = static_cast<int>(points.size());
  ceres::AutoDiffCostFunction<OccupiedSpaceCost, ceres::DYNAMIC, 3> cost(
      new OccupiedSpaceCost(occupied_space_weight / std::sqrt(double(n)), points, grid), n);
  const double x[3] = {pose.translation().x(), pose.translation().y(), pose.yaw_rad()};
  const double* parameters[1] = {x};
  std::vector<double> residuals(n), jacobian(static_cast<size_t>(n) * 3);
  double* jacobians[1] = {jacobian.data()};
  if (!cost.Evaluate(parameters, residuals.data(), jacobians)) return Eigen::Matrix3d::Zero();
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> j(
      jacobian.data(), n, 3);
  return j.transpose() * j;
}

double RotationInformation(const ProbabilityGrid& grid, const PointCloud& points,
                           const Rigid2d& pose, double occupied_space_weight,
                           double translation_weight) {
  if (points.empty()) return 0;
  Eigen::Matrix3d h = MapTermHessian(grid, points, pose, occupied_space_weight);
  h(0, 0) += translation_weight * translation_weight;
  h(1, 1) += translation_weight * translation_weight;
  const Eigen::Matrix2d h_xx = h.topLeftCorner<2, 2>();
  const Eigen::Vector2d h_xt = h.topRightCorner<2, 1>();
  const double info = h(2, 2) - h_xt.dot(h_xx.ldlt().solve(h_xt));
  return std::max(0.0, info);
}

double AdaptiveRotationWeight(double info, double base_weight, double informative_weight,
                              double info_low, double info_high) {
  if (informative_weight <= 0 || !(info > info_low)) return base_weight;
  if (info >= info_high) return informative_weight;
  const double f = std::log(info / info_low) / std::log(info_high / info_low);
  return std::exp((1 - f) * std::log(base_weight) + f * std::log(informative_weight));
}

PrecomputationStack::PrecomputationStack(const ProbabilityGrid& grid, int depth) {
  depth = std::max(1, depth);
  offset_ = (1 << (depth - 1)) - 1;
  width_ = grid.width() + offset_;
  height_ = grid.height() + offset_;
  levels_.resize(depth);
  // Level 0: the grid itself (shifted by offset_).
  auto& l0 = levels_[0];
  l0.assign(static_cast<size_t>(width_) * height_, 0);
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      const float p = grid.RawAt(static_cast<size_t>(y) * grid.width() + x);
      if (p == 0.f) continue;
      const float v = (p - kMinProbability) / (kMaxProbability - kMinProbability) * 255.f;
      l0[static_cast<size_t>(y + offset_) * width_ + x + offset_] =
          static_cast<uint8_t>(std::lround(std::min(255.f, std::max(0.f, v))));
    }
  }
  // Level h from level h-1: max of the four half-windows starting at (x, y), (x+s, y), ...,
  // as a max along rows (x, x+s) and then along columns (y, y+s).
  std::vector<uint8_t> row_max(static_cast<size_t>(width_) * height_);
  for (int h = 1; h < depth; ++h) {
    const int s = 1 << (h - 1);
    const auto& prev = levels_[h - 1];
    auto& cur = levels_[h];
    for (int y = 0; y < height_; ++y) {
      const uint8_t* in = &prev[static_cast<size_t>(y) * width_];
      uint8_t* out = &row_max[static_cast<size_t>(y) * width_];
      for (int x = 0; x + s < width_; ++x) out[x] = std::max(in[x], in[x + s]);
      for (int x = std::max(0, width_ - s); x < width_; ++x) out[x] = in[x];
    }
    cur.resize(prev.size());
    for (int y = 0; y < height_; ++y) {
      const uint8_t* a = &row_max[static_cast<size_t>(y) * width_];
      uint8_t* out = &cur[static_cast<size_t>(y) * width_];
      if (y + s < height_) {
        const uint8_t* b = &row_max[static_cast<size_t>(y + s) * width_];
        for (int x = 0; x < width_; ++x) out[x] = std::max(a[x], b[x]);
      } else {
        std::copy(a, a + width_, out);
      }
    }
  }
  // Level h is now the max over [x, x + 2^h) when read at (x, y) in shifted coordinates, i.e.
  // over original cells [x - offset_, ...]: Value() shifts back by offset_.
}

namespace {

struct Candidate {
  int angle_index;
  int x, y;  // cell offsets
  double score;
};

}  // namespace

bool BranchAndBoundMatch(const ProbabilityGrid& grid, const PrecomputationStack& stack,
                         const PointCloud& points, const Rigid2d& initial,
                         const BranchAndBoundOptions& options, double min_score, Rigid2d* pose,
                         double* score) {
  if (points.empty()) return false;
  const double res = grid.resolution();
  const DiscreteWindow window = Discretize(points, res, options.linear_window_m,
                                           options.angular_window_rad, options.step_range_cap_m);
  const double angle_step = window.angle_step;
  const int num_angles = window.num_angles;
  const int w = window.cells;
  std::vector<std::vector<Eigen::Array2i>> scans(2 * num_angles + 1);
  for (int k = -num_angles; k <= num_angles; ++k) {
    DiscretizeScan(grid, points, initial.yaw_rad() + k * angle_step, initial.translation(),
                   &scans[k + num_angles]);
  }
  const double n = static_cast<double>(points.size());
  // Integer score thresholds: sum of 0..255 values over points.
  auto to_probability = [&](double sum) {
    return kMinProbability + (kMaxProbability - kMinProbability) * sum / (255.0 * n);
  };
  // Bounding box of each rotated scan's cells: a candidate whose shifted box lies inside the
  // stack is scored without per-point bounds checks.
  std::vector<Eigen::Array4i> boxes(scans.size());  // min x, min y, max x, max y
  for (size_t a = 0; a < scans.size(); ++a) {
    Eigen::Array4i b(INT_MAX, INT_MAX, INT_MIN, INT_MIN);
    for (const auto& cell : scans[a]) {
      b = Eigen::Array4i(std::min(b[0], cell.x()), std::min(b[1], cell.y()),
                         std::max(b[2], cell.x()), std::max(b[3], cell.y()));
    }
    boxes[a] = b;
  }
  // Each rotated scan's cells as offsets into a level's storage: inside the stack a candidate's
  // score is a sum of bytes at (candidate's index + offset), with no per-point index arithmetic.
  std::vector<std::vector<ptrdiff_t>> offsets(scans.size());
  const ptrdiff_t origin = stack.Index(0, 0);
  for (size_t a = 0; a < scans.size(); ++a) {
    offsets[a].reserve(scans[a].size());
    for (const auto& cell : scans[a])
      offsets[a].push_back(stack.Index(cell.x(), cell.y()) - origin);
  }
  auto score_of = [&](int level, const Candidate& c) {
    int64_t sum = 0;
    const auto& cells = scans[c.angle_index];
    const Eigen::Array4i& b = boxes[c.angle_index];
    if (stack.Contains(b[0] + c.x, b[1] + c.y) && stack.Contains(b[2] + c.x, b[3] + c.y)) {
      const uint8_t* level_cells = stack.Level(level);
      const ptrdiff_t base = stack.Index(c.x, c.y);
      for (const ptrdiff_t offset : offsets[c.angle_index]) sum += level_cells[base + offset];
    } else {
      for (const auto& cell : cells) sum += stack.Value(level, cell.x() + c.x, cell.y() + c.y);
    }
    return to_probability(static_cast<double>(sum));
  };
  const int top = stack.depth() - 1;
  const int top_step = 1 << top;
  std::vector<Candidate> candidates;
  for (size_t a = 0; a < scans.size(); ++a) {
    for (int y = -w; y <= w; y += top_step) {
      for (int x = -w; x <= w; x += top_step) {
        Candidate c{static_cast<int>(a), x, y, 0};
        c.score = score_of(top, c);
        candidates.push_back(c);
      }
    }
  }
  Candidate best{-1, 0, 0, min_score};
  // Depth-first branch and bound, best-first at each level.
  std::function<void(Candidate*, Candidate*, int)> search = [&](Candidate* first, Candidate* last,
                                                                int level) {
    std::sort(first, last,
              [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
    for (const Candidate* c = first; c != last; ++c) {
      if (c->score <= best.score) break;
      if (level == 0) {
        best = *c;
        break;  // sorted: the first leaf above the bound is the best of this set
      }
      const int half = 1 << (level - 1);
      std::array<Candidate, 4> children;
      int num_children = 0;
      const Eigen::Array4i& b = boxes[c->angle_index];
      if (c->x + half <= w && c->y + half <= w && stack.Contains(b[0] + c->x, b[1] + c->y) &&
          stack.Contains(b[2] + c->x + half, b[3] + c->y + half)) {
        // All four children lie inside the stack: their sums in one pass over the scan's cells
        // (one offset read, four independent loads per cell).
        const uint8_t* level_cells = stack.Level(level - 1);
        const ptrdiff_t base = stack.Index(c->x, c->y);
        const ptrdiff_t right = half, down = stack.Index(0, half) - stack.Index(0, 0);
        int64_t sum[4] = {0, 0, 0, 0};
        for (const ptrdiff_t offset : offsets[c->angle_index]) {
          const uint8_t* cell = level_cells + base + offset;
          sum[0] += cell[0];
          sum[1] += cell[right];
          sum[2] += cell[down];
          sum[3] += cell[down + right];
        }
        for (int i = 0; i < 4; ++i) {
          children[i] = Candidate{c->angle_index, c->x + (i & 1) * half, c->y + (i >> 1) * half,
                                  to_probability(static_cast<double>(sum[i]))};
        }
        search(children.data(), children.data() + 4, level - 1);
        continue;
      }
      for (int dy : {0, half}) {
        if (c->y + dy > w) continue;
        for (int dx : {0, half}) {
          if (c->x + dx > w) continue;
          Candidate child{c->angle_index, c->x + dx, c->y + dy, 0};
          child.score = score_of(level - 1, child);
          children[num_children++] = child;
        }
      }
      search(children.data(), children.data() + num_children, level - 1);
    }
  };
  search(candidates.data(), candidates.data() + candidates.size(), top);
  if (best.angle_index < 0) return false;
  *pose = Rigid2d(initial.translation() + Eigen::Vector2d(best.x * res, best.y * res),
                  initial.yaw_rad() + (best.angle_index - num_angles) * angle_step);
  if (score) *score = best.score;
  return true;
}

bool OnWindowBoundary(const ProbabilityGrid& grid, const PointCloud& points, const Rigid2d& initial,
                      const BranchAndBoundOptions& options, const Rigid2d& found) {
  const double res = grid.resolution();
  const DiscreteWindow window = Discretize(points, res, options.linear_window_m,
                                           options.angular_window_rad, options.step_range_cap_m);
  const Eigen::Vector2d cells = (found.translation() - initial.translation()) / res;
  const double turn = std::remainder(found.yaw_rad() - initial.yaw_rad(), 2 * M_PI);
  return std::lround(std::abs(cells.x())) >= window.cells ||
         std::lround(std::abs(cells.y())) >= window.cells ||
         std::lround(std::abs(turn) / window.angle_step) >= window.num_angles;
}

}  // namespace slam
}  // namespace sarmap
