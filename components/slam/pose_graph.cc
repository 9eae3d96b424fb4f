#include "slam/pose_graph.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

namespace sarmap {
namespace slam {
namespace {

template <typename T>
T WrapAngle(const T& a) {
  const T two_pi = T(2.0 * M_PI);
  return a - two_pi * ceres::floor((a + T(M_PI)) / two_pi);
}

class RelativePoseCost {
 public:
  RelativePoseCost(const Rigid2d& z, double wt, double wr)
      : zx_(z.translation().x()), zy_(z.translation().y()), zt_(z.yaw_rad()), wt_(wt), wr_(wr) {}
  template <typename T>
  bool operator()(const T* const a, const T* const b, T* r) const {
    const T c = ceres::cos(a[2]), s = ceres::sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    r[0] = wt_ * (c * dx + s * dy - zx_);
    r[1] = wt_ * (-s * dx + c * dy - zy_);
    r[2] = wr_ * WrapAngle(b[2] - a[2] - zt_);
    return true;
  }

 private:
  double zx_, zy_, zt_, wt_, wr_;
};

struct Blocks {
  std::vector<std::array<double, 3>> nodes, submaps;
};

void BuildProblem(const std::vector<Constraint>& constraints, Blocks* b, ceres::Problem* problem,
                  const PoseGraphOptions& options, const CovarianceModel* model = nullptr) {
  for (auto& p : b->submaps) problem->AddParameterBlock(p.data(), 3);
  for (auto& p : b->nodes) problem->AddParameterBlock(p.data(), 3);
  if (!b->submaps.empty()) problem->SetParameterBlockConstant(b->submaps[0].data());
  for (const Constraint& c : constraints) {
    double* from;
    double* to;
    if (c.kind == Constraint::INTRA_SUBMAP || c.kind == Constraint::LOOP_CLOSURE) {
      if (c.from >= static_cast<int>(b->submaps.size()) || c.to >= static_cast<int>(b->nodes.size())) continue;
      from = b->submaps[c.from].data();
      to = b->nodes[c.to].data();
    } else {
      if (c.from >= static_cast<int>(b->nodes.size()) || c.to >= static_cast<int>(b->nodes.size())) continue;
      from = b->nodes[c.from].data();
      to = b->nodes[c.to].data();
    }
    ceres::LossFunction* loss =
        c.kind == Constraint::LOOP_CLOSURE ? new ceres::HuberLoss(options.huber_scale) : nullptr;
    const auto [wt, wr] = model ? model->Weights(c) : std::make_pair(c.translation_weight, c.rotation_weight);
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<RelativePoseCost, 3, 3, 3>(new RelativePoseCost(c.relative, wt, wr)),
        loss, from, to);
  }
}

Blocks ToBlocks(const std::vector<Rigid2d>& nodes, const std::vector<Rigid2d>& submaps) {
  Blocks b;
  for (const auto& p : nodes) b.nodes.push_back({p.translation().x(), p.translation().y(), p.yaw_rad()});
  for (const auto& p : submaps) b.submaps.push_back({p.translation().x(), p.translation().y(), p.yaw_rad()});
  return b;
}

}  // namespace

const ConstraintNoise& CovarianceModel::For(int kind) const {
  switch (kind) {
    case Constraint::INTRA_SUBMAP: return intra_submap;
    case Constraint::LOOP_CLOSURE: return loop_closure;
    case Constraint::ODOMETRY: return odometry;
    default: return local_slam;
  }
}

std::pair<double, double> CovarianceModel::Weights(const Constraint& c) const {
  const ConstraintNoise& n = For(c.kind);
  return {n.translation_sigma_m > 0 ? 1.0 / n.translation_sigma_m : c.translation_weight,
          n.rotation_sigma_rad > 0 ? 1.0 / n.rotation_sigma_rad : c.rotation_weight};
}

OptimisationSummary OptimisePoseGraph(const std::vector<Constraint>& constraints,
                                      std::vector<Rigid2d>* node_poses,
                                      std::vector<Rigid2d>* submap_poses,
                                      const PoseGraphOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Blocks b = ToBlocks(*node_poses, *submap_poses);
  ceres::Problem problem;
  BuildProblem(constraints, &b, &problem, options);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  for (size_t i = 0; i < b.nodes.size(); ++i) {
    (*node_poses)[i] = Rigid2d(b.nodes[i][0], b.nodes[i][1], b.nodes[i][2]);
  }
  for (size_t i = 0; i < b.submaps.size(); ++i) {
    (*submap_poses)[i] = Rigid2d(b.submaps[i][0], b.submaps[i][1], b.submaps[i][2]);
  }
  OptimisationSummary out;
  out.iterations = static_cast<int>(summary.iterations.size());
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

bool NodeCovariance(const std::vector<Constraint>& constraints,
                    const std::vector<Rigid2d>& node_poses,
                    const std::vector<Rigid2d>& submap_poses, const std::vector<int>& node_ids,
                    Eigen::MatrixXd* covariance, const PoseGraphOptions& options,
                    const CovarianceModel& model) {
  Blocks b = ToBlocks(node_poses, submap_poses);
  ceres::Problem problem;
  BuildProblem(constraints, &b, &problem, options, &model);
  ceres::Covariance::Options cov_options;
  cov_options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  cov_options.algorithm_type = ceres::SPARSE_QR;
  cov_options.num_threads = 1;
  ceres::Covariance cov(cov_options);
  // ceres::Covariance refuses repeated blocks: compute over the distinct nodes, then expand.
  std::vector<int> unique_ids;
  for (int id : node_ids) {
    if (id < 0 || id >= static_cast<int>(b.nodes.size())) return false;
    if (std::find(unique_ids.begin(), unique_ids.end(), id) == unique_ids.end()) unique_ids.push_back(id);
  }
  std::vector<const double*> blocks;
  for (int id : unique_ids) blocks.push_back(b.nodes[id].data());
  if (!cov.Compute(blocks, &problem)) return false;
  const int u = static_cast<int>(blocks.size());
  std::vector<double> full(9 * u * u);
  if (!cov.GetCovarianceMatrix(blocks, full.data())) return false;
  const int n = static_cast<int>(node_ids.size());
  covariance->resize(3 * n, 3 * n);
  std::vector<int> index(n);
  for (int i = 0; i < n; ++i) {
    index[i] = static_cast<int>(std::find(unique_ids.begin(), unique_ids.end(), node_ids[i]) - unique_ids.begin());
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          (*covariance)(3 * i + r, 3 * j + c) = full[(3 * index[i] + r) * 3 * u + 3 * index[j] + c];
        }
      }
    }
  }
  return true;
}

}  // namespace slam
}  // namespace sarmap
