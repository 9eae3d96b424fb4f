#include "sound_map/joint_optimizer.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <memory>

#include "sound_map/joint_solver_options.h"

namespace sarmap {
namespace sound_map {

namespace {

// e = L (pose_i^-1 pose_j - delta), L the square-root information.
struct OdometryCost {
  Pose2 delta;
  Eigen::Matrix3d sqrt_info;
  template <class T>
  bool operator()(const T* a, const T* b, T* r) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    T e[3] = {c * dx + s * dy - T(delta.x), -s * dx + c * dy - T(delta.y),
              WrapAngle(T(b[2] - a[2] - T(delta.yaw)))};
    for (int i = 0; i < 3; ++i) r[i] = T(sqrt_info(i, 0)) * e[0] + T(sqrt_info(i, 1)) * e[1] + T(sqrt_info(i, 2)) * e[2];
    return true;
  }
};

struct RangeBearingCost {
  Eigen::Vector2d z;
  Eigen::Matrix2d sqrt_info;
  template <class T>
  bool operator()(const T* pose, const T* lm, T* r) const {
    T h[2];
    RangeBearing(pose, lm, h);
    const T e0 = h[0] - T(z[0]);
    const T e1 = WrapAngle(T(h[1] - T(z[1])));
    r[0] = T(sqrt_info(0, 0)) * e0 + T(sqrt_info(0, 1)) * e1;
    r[1] = T(sqrt_info(1, 0)) * e0 + T(sqrt_info(1, 1)) * e1;
    return true;
  }
};

// Sound edge: (expected bearing - observed) / sigma.
template <int kObs>
struct SoundCost {
  Eigen::Vector2d z;
  double inv_sigma;
  ArrayMount mount;
  template <class T>
  bool operator()(const T* pose, const T* src, T* r) const {
    T h[2];
    PointObservation(pose, src, kObs == 2, mount, h);
    r[0] = WrapAngle(T(h[0] - T(z[0]))) * T(inv_sigma);
    if (kObs == 2) r[1] = (h[1] - T(z[1])) * T(inv_sigma);
    return true;
  }
};

Eigen::Matrix3d SqrtInfo3(const Eigen::Matrix3d& cov) {
  return Eigen::Matrix3d(cov.inverse().llt().matrixU());
}
Eigen::Matrix2d SqrtInfo2(const Eigen::Matrix2d& cov) {
  return Eigen::Matrix2d(cov.inverse().llt().matrixU());
}

}  // namespace

bool IntersectRays(const std::vector<Eigen::Vector3d>& origins, const std::vector<Eigen::Vector3d>& dirs,
                   double fallback_range_m, Eigen::Vector3d* point) {
  if (origins.empty()) return false;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < origins.size(); ++i) {
    const Eigen::Matrix3d m = Eigen::Matrix3d::Identity() - dirs[i] * dirs[i].transpose();
    a += m;
    b += m * origins[i];
  }
  *point = origins[0] + fallback_range_m * dirs[0];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
  // Nearly parallel rays leave the depth unconstrained.
  if (eig.eigenvalues().minCoeff() < 1e-3 * static_cast<double>(origins.size())) return false;
  const Eigen::Vector3d sol = a.ldlt().solve(b);
  // The intersection should be in front of the rays.
  if ((sol - origins[0]).dot(dirs[0]) <= 0) return false;
  *point = sol;
  return true;
}

JointProblem2d JointProblemFromSimulation(const Sim2dData& d, bool use_landmarks) {
  JointProblem2d p;
  p.three_d = d.config.three_d;
  p.mount = d.mount;
  p.poses.push_back(d.truth[0]);  // the start is known (gauge)
  const Eigen::Matrix3d odo_cov = d.odometry_covariance();
  for (size_t k = 1; k < d.truth.size(); ++k) {
    p.poses.push_back(Compose(p.poses.back(), d.odometry[k]));
    p.odometry.push_back({static_cast<int>(k - 1), static_cast<int>(k), d.odometry[k], odo_cov});
  }
  const Eigen::Matrix2d lm_cov =
      Eigen::Vector2d(d.config.landmark_sigma_m * d.config.landmark_sigma_m,
                      d.config.landmark_sigma_rad * d.config.landmark_sigma_rad).asDiagonal();
  p.landmarks.assign(d.landmarks.size(), Eigen::Vector2d::Zero());
  std::vector<bool> lm_seen(d.landmarks.size(), false);
  if (use_landmarks) {
    // Incremental initial guess: each pose from its predecessor and odometry, refined
    // against the landmarks already placed (a 3-parameter Ceres solve), then its new
    // landmarks placed from it. Dead reckoning alone drifts far at 5 deg per step.
    for (size_t k = 0; k < d.truth.size(); ++k) {
      if (k > 0) {
        Eigen::Vector3d x = Compose(p.poses[k - 1], d.odometry[k]).vec();
        ceres::Problem local;
        Eigen::Vector3d prev = p.poses[k - 1].vec();
        local.AddResidualBlock(new ceres::AutoDiffCostFunction<OdometryCost, 3, 3, 3>(
                                   new OdometryCost{d.odometry[k], SqrtInfo3(odo_cov)}),
                               nullptr, prev.data(), x.data());
        local.SetParameterBlockConstant(prev.data());
        int used = 0;
        for (const auto& o : d.landmark_obs[k]) {
          if (!lm_seen[o.id]) continue;
          local.AddResidualBlock(new ceres::AutoDiffCostFunction<RangeBearingCost, 2, 3, 2>(
                                     new RangeBearingCost{o.z, SqrtInfo2(lm_cov)}),
                                 new ceres::HuberLoss(3.0), x.data(), p.landmarks[o.id].data());
          local.SetParameterBlockConstant(p.landmarks[o.id].data());
          ++used;
        }
        if (used > 0) {
          ceres::Solver::Options so;
          so.linear_solver_type = ceres::DENSE_QR;
          so.max_num_iterations = 20;
          so.logging_type = ceres::SILENT;
          ceres::Solver::Summary sum;
          ceres::Solve(so, &local, &sum);
        }
        p.poses[k] = Pose2::FromVec(x);
      }
      for (const auto& o : d.landmark_obs[k]) {
        if (!lm_seen[o.id]) {
          const Pose2& x = p.poses[k];
          p.landmarks[o.id] = Eigen::Vector2d(x.x + o.z[0] * std::cos(x.yaw + o.z[1]),
                                              x.y + o.z[0] * std::sin(x.yaw + o.z[1]));
          lm_seen[o.id] = true;
        }
        p.landmark_edges.push_back({static_cast<int>(k), static_cast<int>(o.id), o.z, lm_cov});
      }
    }
  }
  for (size_t k = 0; k < d.truth.size(); ++k)
    for (const auto& o : d.sound_obs[k])
      p.sound_edges.push_back({static_cast<int>(k), static_cast<int>(o.source), o.z, d.config.sound_sigma_rad});
  p.sources.assign(d.sources.size(), Eigen::Vector3d::Zero());
  TriangulateSources(&p);
  return p;
}

void TriangulateSources(JointProblem2d* p) {
  const size_t n = p->sources.size();
  std::vector<std::vector<Eigen::Vector3d>> origins(n), dirs(n);
  for (const auto& e : p->sound_edges) {
    const Pose2& x = p->poses[e.pose];
    double c[2];
    const double pose[3] = {x.x, x.y, x.yaw};
    ArrayOrigin(pose, p->mount, c);
    const double az = x.yaw + p->mount.yaw_rad + e.z[0];
    const double el = p->three_d ? e.z[1] : 0.0;
    origins[e.source].emplace_back(c[0], c[1], p->mount.z_m);
    dirs[e.source].emplace_back(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  }
  p->source_observed.assign(n, false);
  for (size_t j = 0; j < n; ++j) {
    if (origins[j].empty()) continue;
    p->source_observed[j] = true;
    IntersectRays(origins[j], dirs[j], 3.0, &p->sources[j]);
  }
}

JointProblem2d JointProblemFromLog(const std::vector<Pose2>& poses, const std::vector<std::vector<LogBearing>>& bearings,
                                   const std::vector<Eigen::Vector3d>& initial_sources, const ArrayMount& mount,
                                   bool three_d, const LogJointOptions& o) {
  JointProblem2d p;
  p.three_d = three_d;
  p.mount = mount;
  p.poses = poses;
  p.sources = initial_sources;
  p.source_observed.assign(initial_sources.size(), false);
  p.sound_huber_sigmas = o.huber_sigmas;
  const double deg = M_PI / 180;
  for (size_t k = 1; k < poses.size(); ++k) {
    JointProblem2d::Odometry e;
    e.from = static_cast<int>(k - 1);
    e.to = static_cast<int>(k);
    e.delta = Between(poses[k - 1], poses[k]);
    const double d = std::hypot(e.delta.x, e.delta.y);
    const double st = o.odometry_sigma_floor_m + o.odometry_sigma_m_per_m * d;
    const double sr = (o.odometry_sigma_floor_deg + o.odometry_sigma_deg_per_m * d) * deg;
    e.covariance = Eigen::Vector3d(st * st, st * st, sr * sr).asDiagonal();
    p.odometry.push_back(e);
  }
  for (size_t k = 0; k < poses.size() && k < bearings.size(); ++k) {
    const double pose[3] = {poses[k].x, poses[k].y, poses[k].yaw};
    for (const LogBearing& b : bearings[k]) {
      const double sigma = std::max(b.sigma_rad, o.doa_sigma_floor_deg * deg);
      int best = -1;
      double best_chi2 = o.gate_chi2;
      for (size_t j = 0; j < initial_sources.size(); ++j) {
        double h[2];
        PointObservation(pose, initial_sources[j].data(), three_d, mount, h);
        double chi2 = std::pow(WrapAngle(b.azimuth_rad - h[0]) / sigma, 2);
        if (three_d) chi2 += std::pow((b.elevation_rad - h[1]) / sigma, 2);
        if (chi2 < best_chi2) best_chi2 = chi2, best = static_cast<int>(j);
      }
      if (best < 0) continue;
      JointProblem2d::SoundEdge e;
      e.pose = static_cast<int>(k);
      e.source = best;
      e.z = three_d ? Eigen::VectorXd(Eigen::Vector2d(b.azimuth_rad, b.elevation_rad))
                    : Eigen::VectorXd(Eigen::VectorXd::Constant(1, b.azimuth_rad));
      e.sigma_rad = sigma;
      p.sound_edges.push_back(e);
      p.source_observed[best] = true;
    }
  }
  return p;
}

JointReport SolveJointFromLog(const std::vector<Pose2>& poses, const std::vector<std::vector<LogBearing>>& bearings,
                              const std::vector<Eigen::Vector3d>& initial_sources, const ArrayMount& mount,
                              bool three_d, const LogJointOptions& options, JointProblem2d* problem, int rounds) {
  std::vector<Eigen::Vector3d> sources = initial_sources;
  JointReport total;
  size_t last_edges = static_cast<size_t>(-1);
  for (int round = 0; round < std::max(1, rounds); ++round) {
    *problem = JointProblemFromLog(poses, bearings, sources, mount, three_d, options);
    const JointReport r = SolveJoint(problem, 100);
    total.solve_seconds += r.solve_seconds;
    total.iterations += r.iterations;
    total.usable = r.usable;
    if (round == 0) total.initial_cost = r.initial_cost;
    total.final_cost = r.final_cost;
    if (problem->sound_edges.size() == last_edges) break;
    last_edges = problem->sound_edges.size();
    sources = problem->sources;
  }
  return total;
}

JointReport SolveJoint(JointProblem2d* p, int max_iterations) {
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<Eigen::Vector3d> pose_params(p->poses.size());
  for (size_t i = 0; i < p->poses.size(); ++i) pose_params[i] = p->poses[i].vec();
  for (const auto& e : p->odometry) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<OdometryCost, 3, 3, 3>(
                                 new OdometryCost{e.delta, SqrtInfo3(e.covariance)}),
                             nullptr, pose_params[e.from].data(), pose_params[e.to].data());
  }
  for (const auto& e : p->landmark_edges) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RangeBearingCost, 2, 3, 2>(
                                 new RangeBearingCost{e.z, SqrtInfo2(e.covariance)}),
                             nullptr, pose_params[e.pose].data(), p->landmarks[e.landmark].data());
  }
  for (const auto& e : p->sound_edges) {
    if (!p->use_sound_edges) break;
    Eigen::Vector2d z(e.z[0], e.z.size() > 1 ? e.z[1] : 0.0);
    ceres::LossFunction* loss = p->sound_huber_sigmas > 0 ? new ceres::HuberLoss(p->sound_huber_sigmas) : nullptr;
    if (p->three_d) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SoundCost<2>, 2, 3, 3>(
                                   new SoundCost<2>{z, 1.0 / e.sigma_rad, p->mount}),
                               loss, pose_params[e.pose].data(), p->sources[e.source].data());
    } else {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SoundCost<1>, 1, 3, 2>(
                                   new SoundCost<1>{z, 1.0 / e.sigma_rad, p->mount}),
                               loss, pose_params[e.pose].data(), p->sources[e.source].data());
    }
  }
  if (!pose_params.empty() && problem.HasParameterBlock(pose_params[0].data()))
    problem.SetParameterBlockConstant(pose_params[0].data());
  const ceres::Solver::Options options = JointSolverOptions(max_iterations);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (size_t i = 0; i < p->poses.size(); ++i) p->poses[i] = Pose2::FromVec(pose_params[i]);
  JointReport report;
  report.solve_seconds = summary.total_time_in_seconds;
  report.iterations = static_cast<int>(summary.iterations.size());
  report.usable = summary.IsSolutionUsable();
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  return report;
}

}  // namespace sound_map
}  // namespace sarmap
