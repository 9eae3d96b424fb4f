// Calibration of start offsets and clock drifts from a static source heard by an array that
// moves with known poses (see CalibrateWithArrayPoses in calibration.h for the model and why).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <ceres/covariance.h>

#include "mic_calibrate/calibration.h"
#include "mic_calibrate/solver_summary.h"

namespace sarmap {
namespace mic_calibrate {
namespace {

// Internal units as in calibration.cc: offsets in ms, drift in ppm (us per s).
constexpr double kMsPerS = 1e3;
constexpr double kPpm = 1e6;

// TDOA edge of mic n >= 2 at emission k:
//   r = ((|m_n(k) - s| - |m_1(k) - s|) / c + tau_n + t_k delta_n - z_n(k)) / sigma
// from the microphones' offsets to the source, (x, y) in the plane and dz in height.
// clock_n = (tau_n [ms], delta_n [ppm]).
struct TdoaEdge {
  TdoaEdge(double z_s, double t_s, double sigma_s, double c)
      : z_s(z_s), t_s(t_s), inv_sigma(1 / sigma_s), inv_c(1 / c) {}
  template <class T>
  T Residual(const T* clock, const T& xn, const T& yn, double dzn, const T& x1, const T& y1,
             double dz1) const {
    const T dn = sqrt(xn * xn + yn * yn + T(dzn * dzn + 1e-12));
    const T d1 = sqrt(x1 * x1 + y1 * y1 + T(dz1 * dz1 + 1e-12));
    const T predicted = (dn - d1) * inv_c + clock[0] / kMsPerS + t_s * clock[1] / kPpm;
    return (predicted - z_s) * inv_sigma;
  }
  double z_s, t_s, inv_sigma, inv_c;
};

// The edge with the microphones' world positions known. Parameters: clock_n, s = (x, y) [m];
// s_z is known.
struct PosedTdoaResidual : TdoaEdge {
  PosedTdoaResidual(const Eigen::Vector3d& mic_n, const Eigen::Vector3d& mic_1, double s_z,
                    double z_s, double t_s, double sigma_s, double c)
      : TdoaEdge(z_s, t_s, sigma_s, c), mic_n(mic_n), mic_1(mic_1), s_z(s_z) {}
  template <class T>
  bool operator()(const T* clock, const T* src, T* residual) const {
    residual[0] = Residual(clock, T(mic_n.x()) - src[0], T(mic_n.y()) - src[1], mic_n.z() - s_z,
                           T(mic_1.x()) - src[0], T(mic_1.y()) - src[1], mic_1.z() - s_z);
    return true;
  }
  Eigen::Vector3d mic_n, mic_1;
  double s_z;
};

// The same edge with the array pose (x, y, yaw) an unknown (odometry drift): microphone i is
// at (x, y) + R(yaw) a_i in the plane (a_i: its position in the array frame), at height h_i.
struct FreePoseTdoaResidual : TdoaEdge {
  FreePoseTdoaResidual(const Eigen::Vector3d& mic_n, const Eigen::Vector3d& mic_1, double h_n,
                       double h_1, double s_z, double z_s, double t_s, double sigma_s, double c)
      : TdoaEdge(z_s, t_s, sigma_s, c), a_n(mic_n), a_1(mic_1), dz_n(h_n - s_z), dz_1(h_1 - s_z) {}
  template <class T>
  bool operator()(const T* clock, const T* src, const T* pose, T* residual) const {
    const T cy = cos(pose[2]), sy = sin(pose[2]);
    const T xn = pose[0] + cy * a_n.x() - sy * a_n.y() - src[0];
    const T yn = pose[1] + sy * a_n.x() + cy * a_n.y() - src[1];
    const T x1 = pose[0] + cy * a_1.x() - sy * a_1.y() - src[0];
    const T y1 = pose[1] + sy * a_1.x() + cy * a_1.y() - src[1];
    residual[0] = Residual(clock, xn, yn, dz_n, x1, y1, dz_1);
    return true;
  }
  Eigen::Vector3d a_n, a_1;
  double dz_n, dz_1;
};

// Prior on the static source: r = (s - p) / sigma.
struct SourcePrior {
  SourcePrior(const Eigen::Vector2d& p, double sigma) : p(p), inv(1 / sigma) {}
  template <class T>
  bool operator()(const T* s, T* r) const {
    r[0] = (s[0] - p.x()) * inv;
    r[1] = (s[1] - p.y()) * inv;
    return true;
  }
  Eigen::Vector2d p;
  double inv;
};

// Odometry edge between consecutive array poses a = (x, y, yaw)_{k-1}, b = (x, y, yaw)_k:
//   r = W (R(-yaw_a) (p_b - p_a) - d_xy, wrap(yaw_b - yaw_a - d_yaw)),
// d = the given relative motion, W = diag(1/sigma_along, 1/sigma_across, 1/sigma_yaw).
struct OdometryEdge {
  OdometryEdge(const Eigen::Vector3d& d, const Eigen::Vector3d& sigma) : d(d), inv(sigma.cwiseInverse()) {}
  template <class T>
  bool operator()(const T* a, const T* b, T* r) const {
    const T c = cos(a[2]), s = sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    r[0] = (c * dx + s * dy - d.x()) * inv.x();
    r[1] = (-s * dx + c * dy - d.y()) * inv.y();
    T dyaw = b[2] - a[2] - d.z();
    dyaw = atan2(sin(dyaw), cos(dyaw));
    r[2] = dyaw * inv.z();
    return true;
  }
  Eigen::Vector3d d, inv;
};

double Geometric(const Eigen::Vector3d& mic_n, const Eigen::Vector3d& mic_1,
                 const Eigen::Vector3d& s, double c) {
  return ((mic_n - s).norm() - (mic_1 - s).norm()) / c;
}

// Weighted straight-line fit r ~ tau + delta t over the rows with use[k]; false if singular.
bool FitLine(const std::vector<double>& t, const std::vector<double>& r,
             const std::vector<double>& w, const std::vector<char>& use, double* tau,
             double* delta) {
  double s1 = 0, st = 0, stt = 0, sr = 0, str = 0;
  for (size_t k = 0; k < t.size(); ++k) {
    if (!use[k]) continue;
    s1 += w[k];
    st += w[k] * t[k];
    stt += w[k] * t[k] * t[k];
    sr += w[k] * r[k];
    str += w[k] * t[k] * r[k];
  }
  const double det = s1 * stt - st * st;
  if (!(s1 > 0) || !(det > 1e-12 * s1 * s1)) return false;
  *delta = (s1 * str - st * sr) / det;
  *tau = (sr - *delta * st) / s1;
  return true;
}

std::string MicName(int n0) { return "mic " + std::to_string(n0 + 1); }

}  // namespace

CalibrationResult CalibrateWithArrayPoses(const TdoaData& data,
                                          const std::vector<Eigen::Isometry3d>& world_from_array,
                                          const std::vector<Eigen::Vector3d>& mic_positions_m,
                                          const SolverOptions& options) {
  common::ValidateOptions(options);
  const SolverOptions& o = options;
  const int N = data.num_mics, K = data.num_emissions();
  if (N < 2) throw std::invalid_argument("need at least 2 microphones, got " + std::to_string(N));
  if (data.tdoa_s.cols() != N - 1) {
    throw std::invalid_argument("TDOA table has " + std::to_string(data.tdoa_s.cols()) +
                                " columns, expected N-1 = " + std::to_string(N - 1));
  }
  if (static_cast<int>(data.times_s.size()) != K ||
      static_cast<int>(world_from_array.size()) != K) {
    throw std::invalid_argument("need one time and one array pose per emission (" +
                                std::to_string(K) + " emissions, " +
                                std::to_string(data.times_s.size()) + " times, " +
                                std::to_string(world_from_array.size()) + " poses)");
  }
  if (static_cast<int>(mic_positions_m.size()) != N) {
    throw std::invalid_argument("known array poses need the " + std::to_string(N) +
                                " microphone positions in the array frame (--nominal)");
  }
  if (!data.sigma_s.empty() && static_cast<int>(data.sigma_s.size()) != K) {
    throw std::invalid_argument("sigma_s size != K");
  }
  for (double t : data.times_s) {
    if (!std::isfinite(t)) throw UnobservableError("an emission time is NaN/inf");
  }
  for (const auto& p : world_from_array) {
    if (!p.matrix().allFinite()) throw UnobservableError("an array pose is NaN/inf");
  }
  CalibrationResult result;
  result.dim = 2;
  const double c = o.speed_of_sound_mps;
  auto sigma_of = [&](int k) { return data.sigma_s.empty() ? o.tdoa_sigma_s : data.sigma_s[k]; };
  const int clock_params = o.estimate_drift ? 2 : 1;

  // --- What the data can determine before solving. ---
  int missing = 0;
  std::vector<int> finite_per_mic(N, 0);
  for (int k = 0; k < K; ++k)
    for (int n = 1; n < N; ++n) {
      if (std::isfinite(data.tdoa_s(k, n - 1))) ++finite_per_mic[n]; else ++missing;
    }
  if (missing > 0) {
    result.warnings.push_back(std::to_string(missing) + " of " + std::to_string(K * (N - 1)) +
                              " TDOAs are missing (NaN/inf) and were left out");
  }
  {
    std::ostringstream why;
    for (int n = 1; n < N; ++n) {
      if (finite_per_mic[n] < clock_params + 2) {
        why << MicName(n) << " has " << finite_per_mic[n] << " finite TDOAs; at least "
            << clock_params + 2 << " are needed for its start offset"
            << (o.estimate_drift ? " and drift" : "") << " and the source position. ";
      }
    }
    if (!why.str().empty()) throw UnobservableError(why.str() + "(NaN TDOAs carry no information)");
  }
  const int unknowns = 2 + (N - 1) * clock_params;
  if (K * (N - 1) - missing <= unknowns) {
    throw UnobservableError("too few emissions: " + std::to_string(K) + " emissions give " +
                            std::to_string(K * (N - 1) - missing) + " TDOAs for " +
                            std::to_string(unknowns) + " unknowns");
  }
  const auto [tmin, tmax] = std::minmax_element(data.times_s.begin(), data.times_s.end());
  if (o.estimate_drift && !(*tmax > *tmin)) {
    throw UnobservableError("all emissions have the same time: clock drift is unobservable");
  }
  // Did the array move at all? Heading (array x axis) span and translation span.
  double heading_span = 0, travel = 0;
  {
    const Eigen::Vector3d x0 = world_from_array[0].linear().col(0);
    const Eigen::Vector3d p0 = world_from_array[0].translation();
    for (int k = 0; k < K; ++k) {
      const Eigen::Vector3d xk = world_from_array[k].linear().col(0);
      heading_span = std::max(heading_span, std::acos(std::clamp(x0.dot(xk), -1.0, 1.0)));
      travel = std::max(travel, (world_from_array[k].translation() - p0).norm());
    }
  }
  if (heading_span < M_PI / 180 && travel < 0.02) {
    throw UnobservableError(
        "the array never moved (heading span " + std::to_string(heading_span * 180 / M_PI) +
        " deg, travel " + std::to_string(travel) +
        " m): with a static source every emission has the same geometry, so the start "
        "offsets are confounded with the source direction; turn or drive the array");
  }

  // Microphone world positions per emission; the source's known height.
  std::vector<std::vector<Eigen::Vector3d>> mic_world(K, std::vector<Eigen::Vector3d>(N));
  double mean_z = 0;
  for (int k = 0; k < K; ++k)
    for (int n = 0; n < N; ++n) {
      mic_world[k][n] = world_from_array[k] * mic_positions_m[n];
      mean_z += mic_world[k][n].z() / (K * N);
    }
  const double s_z = mean_z + o.static_source_dz_m;

  // --- First guess: grid over s; clocks by (robust) line fit at each node. ---
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<double> w(K);
  for (int k = 0; k < K; ++k) w[k] = 1.0 / (sigma_of(k) * sigma_of(k));
  // Gross outliers (a wrong correlation peak): far from a line fitted to the raw TDOAs,
  // beyond what the geometry can explain (the array's size / c) plus margin.
  double aperture = 0;
  for (int n = 1; n < N; ++n) aperture = std::max(aperture, (mic_positions_m[n] - mic_positions_m[0]).norm());
  std::vector<std::vector<char>> usable(N, std::vector<char>(K, 0));
  for (int n = 1; n < N; ++n) {
    std::vector<double> r(K, 0.0);
    for (int k = 0; k < K; ++k) {
      const double z = data.tdoa_s(k, n - 1);
      usable[n][k] = std::isfinite(z);
      r[k] = usable[n][k] ? z : 0.0;
    }
    for (int pass = 0; pass < 3; ++pass) {
      double tau = 0, delta = 0;
      if (!o.estimate_drift) {
        double s1 = 0, sr = 0;
        for (int k = 0; k < K; ++k)
          if (usable[n][k]) { s1 += w[k]; sr += w[k] * r[k]; }
        tau = sr / std::max(s1, 1e-300);
      } else if (!FitLine(data.times_s, r, w, usable[n], &tau, &delta)) {
        break;
      }
      const double gate = (pass == 0 ? 4.0 : 2.0) * aperture / c + 1e-3;
      for (int k = 0; k < K; ++k) {
        if (!std::isfinite(data.tdoa_s(k, n - 1))) continue;
        usable[n][k] = std::abs(r[k] - tau - delta * data.times_s[k]) <= gate;
      }
    }
  }
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const auto& p : world_from_array) {
    lo = lo.cwiseMin(p.translation().head<2>());
    hi = hi.cwiseMax(p.translation().head<2>());
  }
  lo.array() -= o.grid_margin_m;
  hi.array() += o.grid_margin_m;
  const double gate2 = std::pow(2 * o.loss_scale, 2);  // whitened truncation of the grid cost
  struct Node {
    double cost;
    Eigen::Vector2d s;
    std::vector<double> tau, delta;
  };
  std::vector<Node> nodes;
  std::vector<double> r(K), e(K);
  std::vector<char> use(K);
  for (double x = lo.x(); x <= hi.x() + 1e-9; x += o.grid_step_m) {
    for (double y = lo.y(); y <= hi.y() + 1e-9; y += o.grid_step_m) {
      const Eigen::Vector3d s(x, y, s_z);
      Node node{0, s.head<2>(), std::vector<double>(N, 0.0), std::vector<double>(N, 0.0)};
      if (o.static_source_prior_xy_m.size() == 2) {
        node.cost += (s.head<2>() - Eigen::Vector2d(o.static_source_prior_xy_m[0],
                                                    o.static_source_prior_xy_m[1])).squaredNorm() /
                     std::pow(o.static_source_prior_sigma_m, 2);
      }
      for (int n = 1; n < N; ++n) {
        for (int k = 0; k < K; ++k) {
          use[k] = usable[n][k];
          r[k] = use[k] ? data.tdoa_s(k, n - 1) - Geometric(mic_world[k][n], mic_world[k][0], s, c) : 0;
        }
        double tau = 0, delta = 0, cost = 0;
        for (int pass = 0; pass < 2; ++pass) {
          if (o.estimate_drift) {
            if (!FitLine(data.times_s, r, w, use, &tau, &delta)) break;
          } else {
            double s1 = 0, sr = 0;
            for (int k = 0; k < K; ++k)
              if (use[k]) { s1 += w[k]; sr += w[k] * r[k]; }
            tau = sr / std::max(s1, 1e-300);
          }
          cost = 0;
          for (int k = 0; k < K; ++k) {
            if (!usable[n][k]) continue;
            const double e2 = std::pow(r[k] - tau - delta * data.times_s[k], 2) * w[k];
            cost += std::min(e2, gate2);
            use[k] = e2 < gate2;
          }
        }
        node.cost += cost;
        node.tau[n] = tau;
        node.delta[n] = delta;
      }
      nodes.push_back(std::move(node));
    }
  }
  std::sort(nodes.begin(), nodes.end(), [](const Node& a, const Node& b) { return a.cost < b.cost; });
  std::vector<const Node*> seeds;  // the best distinct minima (0.5 m apart)
  for (const Node& nd : nodes) {
    bool distinct = true;
    for (const Node* sd : seeds) distinct = distinct && (sd->s - nd.s).norm() > 0.5;
    if (distinct) seeds.push_back(&nd);
    if (static_cast<int>(seeds.size()) >= std::max(1, std::min(o.num_starts, 3))) break;
  }

  // --- Ceres from each seed; the best final cost wins. ---
  ceres::Solver::Options sopt;
  sopt.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  sopt.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  sopt.max_num_iterations = std::max(o.max_iterations, 100);
  sopt.parameter_tolerance = 1e-10;
  sopt.function_tolerance = o.function_tolerance;
  sopt.num_threads = o.num_threads;
  sopt.logging_type = ceres::SILENT;
  std::vector<double> best_clocks, best_poses;
  std::vector<Eigen::Isometry3d> corrected_poses;
  Eigen::Vector2d best_s = Eigen::Vector2d::Zero();
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> clocks(2 * N, 0.0);
  double src[2];
  // Pose graph (odometry drift): planar array poses, relative-motion edges.
  const bool free_poses = o.pose_trans_sigma_per_sqrt_m > 0 || o.pose_rot_sigma_per_sqrt_rad > 0 ||
                          o.pose_rot_sigma_per_sqrt_m > 0;
  std::vector<Eigen::Vector3d> given_pose(K);  // x, y, yaw
  for (int k = 0; k < K; ++k) {
    const Eigen::Matrix3d& R = world_from_array[k].linear();
    given_pose[k] = Eigen::Vector3d(world_from_array[k].translation().x(),
                                    world_from_array[k].translation().y(), std::atan2(R(1, 0), R(0, 0)));
  }
  std::vector<double> poses(3 * K);
  auto reset_poses = [&]() {
    for (int k = 0; k < K; ++k)
      for (int i = 0; i < 3; ++i) poses[3 * k + i] = given_pose[k][i];
  };
  reset_poses();
  auto build = [&](ceres::Problem* problem) {
    for (int k = 0; k < K; ++k) {
      for (int n = 1; n < N; ++n) {
        const double z = data.tdoa_s(k, n - 1);
        if (!std::isfinite(z)) continue;
        ceres::LossFunction* loss = nullptr;
        if (o.loss == "huber") loss = new ceres::HuberLoss(o.loss_scale);
        if (o.loss == "cauchy") loss = new ceres::CauchyLoss(o.loss_scale);
        if (free_poses) {
          problem->AddResidualBlock(
              new ceres::AutoDiffCostFunction<FreePoseTdoaResidual, 1, 2, 2, 3>(
                  new FreePoseTdoaResidual(mic_positions_m[n], mic_positions_m[0],
                                           mic_world[k][n].z(), mic_world[k][0].z(), s_z, z,
                                           data.times_s[k], sigma_of(k), c)),
              loss, &clocks[2 * n], src, &poses[3 * k]);
        } else {
          problem->AddResidualBlock(
              new ceres::AutoDiffCostFunction<PosedTdoaResidual, 1, 2, 2>(new PosedTdoaResidual(
                  mic_world[k][n], mic_world[k][0], s_z, z, data.times_s[k], sigma_of(k), c)),
              loss, &clocks[2 * n], src);
        }
      }
    }
    if (free_poses) {
      const double floor_m = 1e-3, floor_rad = 1e-3;
      for (int k = 1; k < K; ++k) {
        const Eigen::Vector3d& a = given_pose[k - 1];
        const Eigen::Vector3d& b = given_pose[k];
        const double ca = std::cos(a.z()), sa = std::sin(a.z());
        const Eigen::Vector2d dp = b.head<2>() - a.head<2>();
        const Eigen::Vector3d d(ca * dp.x() + sa * dp.y(), -sa * dp.x() + ca * dp.y(),
                                std::remainder(b.z() - a.z(), 2 * M_PI));
        const double ds = dp.norm(), dth = std::abs(d.z());
        const double s_yaw = std::sqrt(std::pow(o.pose_rot_sigma_per_sqrt_rad, 2) * dth +
                                       std::pow(o.pose_rot_sigma_per_sqrt_m, 2) * ds + floor_rad * floor_rad);
        const double s_along = std::sqrt(std::pow(o.pose_trans_sigma_per_sqrt_m, 2) * ds + floor_m * floor_m);
        const double s_across = std::sqrt(std::pow(s_yaw * ds / 2, 2) + floor_m * floor_m);
        problem->AddResidualBlock(new ceres::AutoDiffCostFunction<OdometryEdge, 3, 3, 3>(
                                      new OdometryEdge(d, Eigen::Vector3d(s_along, s_across, s_yaw))),
                                  nullptr, &poses[3 * (k - 1)], &poses[3 * k]);
      }
      problem->SetParameterBlockConstant(&poses[0]);  // gauge: the first pose
    }
    if (o.static_source_prior_xy_m.size() == 2) {
      problem->AddResidualBlock(
          new ceres::AutoDiffCostFunction<SourcePrior, 2, 2>(new SourcePrior(
              Eigen::Vector2d(o.static_source_prior_xy_m[0], o.static_source_prior_xy_m[1]),
              o.static_source_prior_sigma_m)),
          nullptr, src);
    }
    if (!o.estimate_drift) {
      for (int n = 1; n < N; ++n)
        if (problem->HasParameterBlock(&clocks[2 * n]))
          problem->SetManifold(&clocks[2 * n], new ceres::SubsetManifold(2, {1}));
    }
  };
  for (size_t i = 0; i < seeds.size(); ++i) {
    for (int n = 1; n < N; ++n) {
      clocks[2 * n] = seeds[i]->tau[n] * kMsPerS;
      clocks[2 * n + 1] = seeds[i]->delta[n] * kPpm;
    }
    src[0] = seeds[i]->s.x();
    src[1] = seeds[i]->s.y();
    reset_poses();
    ceres::Problem problem;
    build(&problem);
    ceres::Solver::Summary summary;
    ceres::Solve(sopt, &problem, &summary);
    const StartSummary ss = SummariseStart(static_cast<int>(i), summary);
    result.total_iterations += ss.iterations;
    result.starts.push_back(ss);
    if (o.verbose) {
      fprintf(stderr, "  start %zu/%zu (grid node %.2f, %.2f): cost %.6g, %d iterations, "
              "source %.3f, %.3f%s\n", i + 1, seeds.size(), seeds[i]->s.x(), seeds[i]->s.y(),
              ss.final_cost, ss.iterations, src[0], src[1], ss.converged ? "" : " (not converged)");
    }
    if (std::isfinite(summary.final_cost) && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best_clocks = clocks;
      best_s = Eigen::Vector2d(src[0], src[1]);
      best_poses = poses;
      result.best_start = static_cast<int>(i);
      result.iterations = ss.iterations;
    }
  }
  result.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.recording_end_s = *tmax;
  if (!std::isfinite(best_cost)) throw std::runtime_error("no start produced a finite cost");
  result.final_cost = best_cost;
  clocks = best_clocks;
  poses = best_poses;
  if (free_poses) {  // the corrected array poses from here on
    for (int k = 0; k < K; ++k) {
      Eigen::Isometry3d w = Eigen::Isometry3d::Identity();
      w.linear() = (Eigen::AngleAxisd(poses[3 * k + 2], Eigen::Vector3d::UnitZ()) *
                    Eigen::AngleAxisd(-given_pose[k].z(), Eigen::Vector3d::UnitZ()))
                       .toRotationMatrix() * world_from_array[k].linear();
      w.translation() = Eigen::Vector3d(poses[3 * k], poses[3 * k + 1], world_from_array[k].translation().z());
      corrected_poses.push_back(w);
      for (int n = 0; n < N; ++n) mic_world[k][n] = w * mic_positions_m[n];
    }
  }
  src[0] = best_s.x();
  src[1] = best_s.y();
  const Eigen::Vector3d s(src[0], src[1], s_z);

  // --- Estimates, residuals. ---
  result.mic_positions_m = mic_positions_m;
  result.start_offsets_s.assign(N, 0.0);
  result.clock_drift.assign(N, 0.0);
  for (int n = 1; n < N; ++n) {
    result.start_offsets_s[n] = clocks[2 * n] / kMsPerS;
    result.clock_drift[n] = clocks[2 * n + 1] / kPpm;
  }
  result.source_positions_m = {s};
  result.tdoa_residual_s = Eigen::MatrixXd::Constant(K, N - 1, std::nan(""));
  for (int k = 0; k < K; ++k) {
    for (int n = 1; n < N; ++n) {
      const double z = data.tdoa_s(k, n - 1);
      if (!std::isfinite(z)) continue;
      result.tdoa_residual_s(k, n - 1) = Geometric(mic_world[k][n], mic_world[k][0], s, c) +
                                         result.start_offsets_s[n] + data.times_s[k] * result.clock_drift[n] - z;
    }
  }
  SetResidualStatistics(&result);
  AssessSolve(data, o, &result);
  const double f = result.variance_factor;

  // --- The bearing of the source in the array frame: does it span enough? ---
  {
    int far = 1;
    for (int n = 1; n < N; ++n)
      if ((mic_positions_m[n] - mic_positions_m[0]).norm() > (mic_positions_m[far] - mic_positions_m[0]).norm()) far = n;
    const Eigen::Vector3d u = (mic_positions_m[far] - mic_positions_m[0]).normalized();
    double off_line = 0;
    for (int n = 0; n < N; ++n) {
      const Eigen::Vector3d d = mic_positions_m[n] - mic_positions_m[0];
      off_line = std::max(off_line, (d - d.dot(u) * u).norm());
    }
    const bool collinear = N == 2 || off_line < 1e-3;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& m : mic_positions_m) centre += m / N;
    std::vector<double> angles;
    for (int k = 0; k < K; ++k) {
      Eigen::Vector3d p = (free_poses ? corrected_poses[k] : world_from_array[k]).inverse() * s - centre;
      if (collinear) {
        angles.push_back(std::acos(std::clamp(p.normalized().dot(u), -1.0, 1.0)));
      } else {
        // In the array's plane (x-y of the array frame), circular span.
        angles.push_back(std::atan2(p.y(), p.x()));
      }
    }
    std::sort(angles.begin(), angles.end());
    double span = angles.back() - angles.front();
    if (!collinear) {
      double largest_gap = 2 * M_PI - span;
      for (size_t i = 1; i < angles.size(); ++i) largest_gap = std::max(largest_gap, angles[i] - angles[i - 1]);
      span = 2 * M_PI - largest_gap;
    }
    result.bearing_span_deg = span * 180 / M_PI;
    if (result.bearing_span_deg < o.min_bearing_span_deg) {
      std::ostringstream why;
      why << "the source's bearing in the array frame spans only " << result.bearing_span_deg
          << " deg (need " << o.min_bearing_span_deg << "): "
          << (collinear ? "with the microphones on one line, " : "")
          << "start offsets and drifts that grow along the array look like a change of the "
             "source direction, which so few bearings cannot separate; turn the array further "
             "(a full turn in place is best) or drive around the source";
      throw UnobservableError(why.str());
    }
  }

  // --- Marginal covariances (robust loss applied, as in the solve). ---
  result.mic_position_cov.assign(N, Eigen::Matrix3d::Zero());
  result.clock_cov.assign(N, Eigen::Matrix2d::Zero());
  result.source_cov.assign(1, Eigen::Matrix3d::Zero());
  if (o.compute_covariance) {
    const auto tc = std::chrono::steady_clock::now();
    ceres::Problem problem;
    build(&problem);
    ceres::Covariance cov(CovarianceOptions(o.num_threads));
    std::vector<std::pair<const double*, const double*>> blocks = {{src, src}};
    for (int n = 1; n < N; ++n)
      if (problem.HasParameterBlock(&clocks[2 * n])) blocks.emplace_back(&clocks[2 * n], &clocks[2 * n]);
    if (!cov.Compute(blocks, &problem)) {
      throw UnobservableError(
          "the Jacobian at the solution is rank deficient (Ceres covariance failed): the source "
          "position, start offsets and drifts are not all determined by these TDOAs and poses "
          "(the array did not turn or move enough relative to the source)");
    }
    Eigen::Matrix<double, 2, 2, Eigen::RowMajor> cs;
    cov.GetCovarianceBlock(src, src, cs.data());
    cs *= f;
    result.source_cov[0].topLeftCorner<2, 2>() = cs;
    std::ostringstream bad;
    if (!(std::sqrt(cs.trace()) <= o.max_position_std_m)) {
      bad << "source position std " << std::sqrt(cs.trace()) << " m; ";
    }
    for (int n = 1; n < N; ++n) {
      if (!problem.HasParameterBlock(&clocks[2 * n])) continue;
      Eigen::Matrix<double, 2, 2, Eigen::RowMajor> m;
      cov.GetCovarianceBlock(&clocks[2 * n], &clocks[2 * n], m.data());
      const Eigen::Matrix2d scale = Eigen::Vector2d(1 / kMsPerS, 1 / kPpm).asDiagonal();
      result.clock_cov[n] = f * scale * m * scale;
      const double std_tau = std::sqrt(std::max(0.0, result.clock_cov[n](0, 0)));
      if (!(std_tau <= o.max_offset_std_s)) bad << MicName(n) << " start-offset std " << std_tau * 1e3 << " ms; ";
    }
    result.has_covariance = true;
    result.covariance_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - tc).count();
    if (!bad.str().empty()) {
      throw UnobservableError("calibration too uncertain to use: " + bad.str() +
                              "(turn or drive the array more around the source)");
    }
  }
  return result;
}

}  // namespace mic_calibrate
}  // namespace sarmap
