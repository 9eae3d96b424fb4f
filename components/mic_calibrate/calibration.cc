#include "mic_calibrate/calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <ceres/covariance.h>
#include <ceres/manifold.h>

#include "mic_calibrate/solver_summary.h"

namespace sarmap {
namespace mic_calibrate {
namespace {

// Internal units keep the normal equations well scaled: positions in m, start offsets in ms,
// clock drift in ppm (us per s). A TDOA residual is then O(1) in every direction.
constexpr double kMsPerS = 1e3;
constexpr double kPpm = 1e6;

// TDOA edge of mic n >= 2 at emission k (eq. 3.18 / 3.30), whitened:
//   r = ((|m_n - s_k| - |s_k|) / c + tau_n + t_k delta_n - z_n(k)) / sigma
// Parameters: m_n (D), clock_n = (tau_n [ms], delta_n [ppm]), s_k (D). Mic 1 is at the origin.
template <int D>
struct TdoaResidual {
  TdoaResidual(double z_s, double t_s, double sigma_s, double c)
      : z_s(z_s), t_s(t_s), inv_sigma(1.0 / sigma_s), inv_c(1.0 / c) {}
  template <class T>
  bool operator()(const T* mic, const T* clock, const T* src, T* residual) const {
    T d_mic2 = T(1e-12), d_ref2 = T(1e-12);  // the epsilon keeps sqrt differentiable at 0
    for (int i = 0; i < D; ++i) {
      d_mic2 += (mic[i] - src[i]) * (mic[i] - src[i]);
      d_ref2 += src[i] * src[i];
    }
    const T predicted = (sqrt(d_mic2) - sqrt(d_ref2)) * inv_c + clock[0] / kMsPerS +
                        t_s * clock[1] / kPpm;
    residual[0] = (predicted - z_s) * inv_sigma;
    return true;
  }
  double z_s, t_s, inv_sigma, inv_c;
};

// The same edge with the analytic Jacobians of eqs. 3.21-3.23 / 3.33-3.36 (in our units):
//   dr/dm = (m - s) / (|m - s| c sigma),  dr/ds = (-(m - s)/|m - s| - s/|s|) / (c sigma),
//   dr/dtau = 1 / (1000 sigma),  dr/ddelta = t / (10^6 sigma).
template <int D>
class TdoaCost : public ceres::SizedCostFunction<1, D, 2, D> {
 public:
  TdoaCost(double z_s, double t_s, double sigma_s, double c)
      : z_s_(z_s), t_s_(t_s), inv_sigma_(1.0 / sigma_s), inv_c_(1.0 / c) {}
  bool Evaluate(double const* const* p, double* residual, double** jac) const override {
    const double* mic = p[0];
    const double* clock = p[1];
    const double* src = p[2];
    double d_mic2 = 1e-12, d_ref2 = 1e-12;
    for (int i = 0; i < D; ++i) {
      d_mic2 += (mic[i] - src[i]) * (mic[i] - src[i]);
      d_ref2 += src[i] * src[i];
    }
    const double d_mic = std::sqrt(d_mic2), d_ref = std::sqrt(d_ref2);
    residual[0] = ((d_mic - d_ref) * inv_c_ + clock[0] / kMsPerS + t_s_ * clock[1] / kPpm - z_s_) *
                  inv_sigma_;
    if (jac) {
      const double g = inv_c_ * inv_sigma_;
      if (jac[0])
        for (int i = 0; i < D; ++i) jac[0][i] = g * (mic[i] - src[i]) / d_mic;
      if (jac[1]) {
        jac[1][0] = inv_sigma_ / kMsPerS;
        jac[1][1] = inv_sigma_ * t_s_ / kPpm;
      }
      if (jac[2])
        for (int i = 0; i < D; ++i) jac[2][i] = g * (-(mic[i] - src[i]) / d_mic - src[i] / d_ref);
    }
    return true;
  }

 private:
  double z_s_, t_s_, inv_sigma_, inv_c_;
};

// Synchronous array: no clock block.
template <int D>
struct SyncTdoaResidual {
  SyncTdoaResidual(double z_s, double sigma_s, double c)
      : z_s(z_s), inv_sigma(1.0 / sigma_s), inv_c(1.0 / c) {}
  template <class T>
  bool operator()(const T* mic, const T* src, T* residual) const {
    T d_mic2 = T(1e-12), d_ref2 = T(1e-12);
    for (int i = 0; i < D; ++i) {
      d_mic2 += (mic[i] - src[i]) * (mic[i] - src[i]);
      d_ref2 += src[i] * src[i];
    }
    residual[0] = ((sqrt(d_mic2) - sqrt(d_ref2)) * inv_c - z_s) * inv_sigma;
    return true;
  }
  double z_s, inv_sigma, inv_c;
};

// Linear array of known spacing, far-field source angle beta_k (eq. 3.49):
//   r = (-x_n cos(beta_k) / c + tau_n + t_k delta_n - z_n(k)) / sigma
struct LinearTdoaResidual {
  LinearTdoaResidual(double z_s, double t_s, double sigma_s, double c, double x_n)
      : z_s(z_s), t_s(t_s), inv_sigma(1.0 / sigma_s), inv_c(1.0 / c), x_n(x_n) {}
  template <class T>
  bool operator()(const T* clock, const T* beta, T* residual) const {
    const T predicted = -x_n * cos(beta[0]) * inv_c + clock[0] / kMsPerS + t_s * clock[1] / kPpm;
    residual[0] = (predicted - z_s) * inv_sigma;
    return true;
  }
  double z_s, t_s, inv_sigma, inv_c, x_n;
};

// Random-walk prior between consecutive source states (eq. 3.15 / 3.46), whitened:
//   r = (s_k - s_{k-1} - motion) / sigma
template <int D>
struct RandomWalkResidual {
  RandomWalkResidual(const Eigen::Vector3d& motion, const Eigen::Vector3d& sigma)
      : motion(motion), inv_sigma(sigma.cwiseInverse()) {}
  template <class T>
  bool operator()(const T* a, const T* b, T* residual) const {
    for (int i = 0; i < D; ++i) residual[i] = (b[i] - a[i] - motion[i]) * inv_sigma[i];
    return true;
  }
  Eigen::Vector3d motion, inv_sigma;
};

// Known microphone height (3d): r = (m_z - h) / sigma.
struct HeightPriorResidual {
  HeightPriorResidual(double height_m, double sigma_m) : h(height_m), inv_sigma(1 / sigma_m) {}
  template <class T>
  bool operator()(const T* m, T* residual) const {
    residual[0] = (m[2] - h) * inv_sigma;
    return true;
  }
  double h, inv_sigma;
};

// All unknowns, in internal units; blocks are stored with stride 3 (positions) and 2 (clocks).
struct State {
  int dim = 2;
  std::vector<double> mics;     // N x 3 (mic 1 unused: fixed at the origin)
  std::vector<double> clocks;   // N x 2 (tau ms, delta ppm; mic 1 unused)
  std::vector<double> sources;  // K x 3, or K x 1 angles (linear)
};

struct Problem {
  std::unique_ptr<ceres::Problem> problem;
  int num_tdoa_residuals = 0;
};

bool IsLinear(const SolverOptions& o) { return o.geometry == "linear"; }

double LinearMicX(const SolverOptions& o, int n) { return n * o.linear_spacing_m; }

Problem Build(const TdoaData& data, const SolverOptions& o, int gx, int gp, State* state,
              bool with_loss) {
  Problem out;
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::TAKE_OWNERSHIP;
  popt.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  out.problem = std::make_unique<ceres::Problem>(popt);
  ceres::Problem& problem = *out.problem;
  const int N = data.num_mics, K = data.num_emissions(), D = o.dim();
  const bool linear = IsLinear(o);
  const int src_stride = linear ? 1 : 3;

  auto make_loss = [&]() -> ceres::LossFunction* {
    if (!with_loss || o.loss == "none") return nullptr;
    if (o.loss == "cauchy") return new ceres::CauchyLoss(o.loss_scale);
    return new ceres::HuberLoss(o.loss_scale);
  };

  for (int k = 0; k < K; ++k) {
    const double sigma = data.sigma_s.empty() ? o.tdoa_sigma_s : data.sigma_s[k];
    double* src = &state->sources[src_stride * k];
    for (int n = 1; n < N; ++n) {
      const double z = data.tdoa_s(k, n - 1);
      if (!std::isfinite(z)) continue;
      double* mic = &state->mics[3 * n];
      double* clock = &state->clocks[2 * n];
      const double t = data.times_s[k];
      ceres::CostFunction* cost = nullptr;
      if (linear) {
        cost = new ceres::AutoDiffCostFunction<LinearTdoaResidual, 1, 2, 1>(
            new LinearTdoaResidual(z, t, sigma, o.speed_of_sound_mps, LinearMicX(o, n)));
        problem.AddResidualBlock(cost, make_loss(), clock, src);
      } else if (o.synchronous) {
        if (D == 2) {
          cost = new ceres::AutoDiffCostFunction<SyncTdoaResidual<2>, 1, 2, 2>(
              new SyncTdoaResidual<2>(z, sigma, o.speed_of_sound_mps));
        } else {
          cost = new ceres::AutoDiffCostFunction<SyncTdoaResidual<3>, 1, 3, 3>(
              new SyncTdoaResidual<3>(z, sigma, o.speed_of_sound_mps));
        }
        problem.AddResidualBlock(cost, make_loss(), mic, src);
      } else {
        if (D == 2) {
          cost = new TdoaCost<2>(z, t, sigma, o.speed_of_sound_mps);
        } else {
          cost = new TdoaCost<3>(z, t, sigma, o.speed_of_sound_mps);
        }
        problem.AddResidualBlock(cost, make_loss(), mic, clock, src);
      }
      ++out.num_tdoa_residuals;
    }
  }
  // Random-walk prior between consecutive source states.
  for (int k = 1; k < K; ++k) {
    double* a = &state->sources[src_stride * (k - 1)];
    double* b = &state->sources[src_stride * k];
    Eigen::Vector3d motion = Eigen::Vector3d::Zero();
    Eigen::Vector3d sigma = Eigen::Vector3d::Constant(linear ? o.random_walk_sigma_rad
                                                             : o.random_walk_sigma_m);
    if (!linear && static_cast<int>(data.motion_m.size()) == K - 1) {
      motion = data.motion_m[k - 1];
      sigma = data.motion_sigma_m[k - 1];
    }
    ceres::CostFunction* cost = nullptr;
    if (linear) {
      cost = new ceres::AutoDiffCostFunction<RandomWalkResidual<1>, 1, 1, 1>(
          new RandomWalkResidual<1>(motion, sigma));
    } else if (D == 2) {
      cost = new ceres::AutoDiffCostFunction<RandomWalkResidual<2>, 2, 2, 2>(
          new RandomWalkResidual<2>(motion, sigma));
    } else {
      cost = new ceres::AutoDiffCostFunction<RandomWalkResidual<3>, 3, 3, 3>(
          new RandomWalkResidual<3>(motion, sigma));
    }
    problem.AddResidualBlock(cost, nullptr, a, b);
  }
  if (!linear && D == 3 && o.height_prior_sigma_m > 0) {
    for (int n = 1; n < N; ++n) {
      if (!problem.HasParameterBlock(&state->mics[3 * n])) continue;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<HeightPriorResidual, 1, 3>(
              new HeightPriorResidual(o.mic_heights_m[n], o.height_prior_sigma_m)),
          nullptr, &state->mics[3 * n]);
    }
  }
  // Known geometry: the positions are data, not unknowns (no gauge needed: they fix the frame).
  if (!linear && o.known_positions) {
    for (int n = 1; n < N; ++n) {
      if (problem.HasParameterBlock(&state->mics[3 * n])) {
        problem.SetParameterBlockConstant(&state->mics[3 * n]);
      }
    }
  }
  // Gauge: mic x on the x axis; (3d) mic plane in z = 0. Mic 1 never enters as a block.
  if (!linear && !o.known_positions) {
    const int ix = gx - 1, ip = gp - 1;
    if (problem.HasParameterBlock(&state->mics[3 * ix])) {
      problem.SetManifold(&state->mics[3 * ix],
                          D == 2 ? new ceres::SubsetManifold(2, {1})
                                 : new ceres::SubsetManifold(3, {1, 2}));
    }
    if (D == 3 && problem.HasParameterBlock(&state->mics[3 * ip])) {
      problem.SetManifold(&state->mics[3 * ip], new ceres::SubsetManifold(3, {2}));
    }
  }
  if (!linear && D == 3 && o.sources_in_gauge_plane) {
    for (int k = 0; k < K; ++k) {
      state->sources[3 * k + 2] = 0;
      problem.SetManifold(&state->sources[3 * k], new ceres::SubsetManifold(3, {2}));
    }
  }
  if (!o.synchronous && !o.estimate_drift) {
    for (int n = 1; n < N; ++n) {
      if (problem.HasParameterBlock(&state->clocks[2 * n])) {
        problem.SetManifold(&state->clocks[2 * n], new ceres::SubsetManifold(2, {1}));
      }
    }
  }
  return out;
}

// Start offsets and drifts from a straight-line fit of each mic's TDOAs against time: the
// geometric part is bounded by the array size / c, so this lands within a few ms.
void InitialiseClocks(const TdoaData& data, const SolverOptions& o, State* state) {
  const int N = data.num_mics, K = data.num_emissions();
  for (int n = 1; n < N; ++n) {
    double s1 = 0, st = 0, stt = 0, sz = 0, stz = 0;
    for (int k = 0; k < K; ++k) {
      const double z = data.tdoa_s(k, n - 1);
      if (!std::isfinite(z)) continue;
      const double t = data.times_s[k];
      s1 += 1;
      st += t;
      stt += t * t;
      sz += z;
      stz += t * z;
    }
    double tau = s1 > 0 ? sz / s1 : 0, delta = 0;
    const double det = s1 * stt - st * st;
    if (o.estimate_drift && s1 >= 2 && det > 1e-12 * s1 * s1) {
      delta = (s1 * stz - st * sz) / det;
      tau = (sz - delta * st) / s1;
    }
    state->clocks[2 * n] = tau * kMsPerS;
    state->clocks[2 * n + 1] = delta * kPpm;
  }
}

void RandomInitialise(const TdoaData& data, const SolverOptions& o, int gx, int gp,
                      std::mt19937_64* rng, State* state) {
  const int N = data.num_mics, K = data.num_emissions(), D = o.dim();
  std::uniform_real_distribution<double> box(-o.init_extent_m, o.init_extent_m);
  state->dim = D;
  state->mics.assign(3 * N, 0.0);
  state->clocks.assign(2 * N, 0.0);
  if (IsLinear(o)) {
    std::uniform_real_distribution<double> angle(0.2, M_PI - 0.2);
    state->sources.assign(K, angle(*rng));
    for (int n = 0; n < N; ++n) state->mics[3 * n] = LinearMicX(o, n);
  } else {
    state->sources.assign(3 * K, 0.0);
    for (int n = 1; n < N; ++n) {
      for (int i = 0; i < D; ++i) state->mics[3 * n + i] = box(*rng);
    }
    // Respect the gauge constraints from the start.
    state->mics[3 * (gx - 1)] = std::abs(state->mics[3 * (gx - 1)]) + 0.05;
    state->mics[3 * (gx - 1) + 1] = 0;
    state->mics[3 * (gx - 1) + 2] = 0;
    if (D == 3) state->mics[3 * (gp - 1) + 2] = 0;
    for (int k = 0; k < K; ++k) {
      for (int i = 0; i < D; ++i) state->sources[3 * k + i] = box(*rng);
    }
  }
  if (!o.synchronous) InitialiseClocks(data, o, state);
}

std::string MicName(int n0) { return "mic " + std::to_string(n0 + 1); }

// What the data can determine at all, before solving. Throws UnobservableError.
void CheckObservability(const TdoaData& data, const SolverOptions& o, std::vector<std::string>* warnings) {
  const int N = data.num_mics, K = data.num_emissions(), D = o.dim();
  const bool linear = IsLinear(o);
  std::ostringstream why;
  // Missing values.
  int missing = 0;
  std::vector<int> finite_per_mic(N, 0);
  for (int k = 0; k < K; ++k) {
    for (int n = 1; n < N; ++n) {
      if (std::isfinite(data.tdoa_s(k, n - 1))) {
        ++finite_per_mic[n];
      } else {
        ++missing;
      }
    }
  }
  if (missing > 0) {
    warnings->push_back(std::to_string(missing) + " of " + std::to_string(K * (N - 1)) +
                        " TDOAs are missing (NaN/inf) and were left out");
  }
  if (!linear) {
    if (N < D + 1) {
      throw UnobservableError("a " + std::to_string(D) + "D array needs at least " +
                              std::to_string(D + 1) + " microphones to fix the frame, got " +
                              std::to_string(N));
    }
    // Each emission adds D source unknowns and gives N-1 TDOAs: positions are only
    // determined by the TDOAs if N-1 > D (otherwise only the random-walk prior would
    // "determine" them).
    if (N - 1 <= D) {
      throw UnobservableError(
          "each emission gives " + std::to_string(N - 1) + " TDOAs but adds " +
          std::to_string(D) + " unknown source coordinates: with " + std::to_string(N) +
          " microphones a " + std::to_string(D) +
          "D array's positions are unobservable from TDOAs (need at least " +
          std::to_string(D + 2) + " microphones)");
    }
  }
  const int clock_params = o.synchronous ? 0 : (o.estimate_drift ? 2 : 1);
  // Counting: unknowns vs independent measurements (the prior adds no absolute information).
  const int gauge = linear ? 0 : (D == 2 ? 3 : 6);
  const int mic_unknowns = (N - 1) * ((linear ? 0 : D) + clock_params) - gauge;
  const int src_unknowns = K * (linear ? 1 : D);
  const int num_obs = K * (N - 1) - missing;
  if (num_obs <= mic_unknowns + src_unknowns) {
    const int per_emission = (N - 1) - (linear ? 1 : D);
    const int k_min = per_emission > 0 ? mic_unknowns / per_emission + 1 : -1;
    std::ostringstream s;
    s << "too few emissions: " << K << " emissions give " << num_obs << " TDOAs for "
      << mic_unknowns << " array unknowns + " << src_unknowns
      << " source unknowns; the array is unobservable";
    if (k_min > 0) s << " (need at least " << k_min << " source positions)";
    throw UnobservableError(s.str());
  }
  const int min_per_mic = std::max(clock_params + (linear ? 0 : D), 1) + 1;
  for (int n = 1; n < N; ++n) {
    if (finite_per_mic[n] < min_per_mic) {
      why << MicName(n) << " has " << finite_per_mic[n] << " finite TDOAs; at least "
          << min_per_mic << " are needed to determine its "
          << (linear ? "" : "position") << (linear || o.synchronous ? "" : ", ")
          << (o.synchronous ? "" : (o.estimate_drift ? "start offset and drift" : "start offset"))
          << " (NaN TDOAs carry no information). ";
    }
  }
  if (!why.str().empty()) throw UnobservableError(why.str());

  if (!o.synchronous && o.estimate_drift) {
    double tmin = 1e300, tmax = -1e300;
    for (double t : data.times_s) {
      tmin = std::min(tmin, t);
      tmax = std::max(tmax, t);
    }
    if (!(tmax > tmin)) {
      throw UnobservableError("all emissions have the same time: clock drift is unobservable");
    }
  }
  // Source motion: after removing what the clocks explain (a constant, plus a line in time
  // with drift), the TDOAs must still vary beyond the noise, or the geometry is confounded
  // with the start offsets (a source that never moves).
  if (!linear) {
    State st;
    st.clocks.assign(2 * N, 0.0);
    InitialiseClocks(data, o, &st);
    double max_std = 0, mean_sigma = 0;
    for (int k = 0; k < K; ++k) mean_sigma += data.sigma_s.empty() ? o.tdoa_sigma_s : data.sigma_s[k];
    mean_sigma /= std::max(K, 1);
    for (int n = 1; n < N; ++n) {
      double s2 = 0;
      int cnt = 0;
      for (int k = 0; k < K; ++k) {
        const double z = data.tdoa_s(k, n - 1);
        if (!std::isfinite(z)) continue;
        double r = z;
        if (o.synchronous) {
          r = z;  // nothing explained by clocks; subtract the mean below
        } else {
          r = z - st.clocks[2 * n] / kMsPerS - data.times_s[k] * st.clocks[2 * n + 1] / kPpm;
        }
        s2 += r * r;
        ++cnt;
      }
      double var = s2 / std::max(cnt, 1);
      if (o.synchronous) {
        double mean = 0;
        for (int k = 0; k < K; ++k) {
          if (std::isfinite(data.tdoa_s(k, n - 1))) mean += data.tdoa_s(k, n - 1);
        }
        mean /= std::max(cnt, 1);
        var -= mean * mean;
      }
      max_std = std::max(max_std, std::sqrt(std::max(var, 0.0)));
    }
    if (max_std < 2.0 * mean_sigma) {
      std::ostringstream s;
      s << "the TDOAs do not vary beyond the noise once "
        << (o.synchronous ? "their mean is"
                          : (o.estimate_drift ? "a start offset and a drift line are"
                                              : "a start offset is"))
        << " removed (largest remaining std " << max_std * 1e3 << " ms vs TDOA sigma "
        << mean_sigma * 1e3
        << " ms): the source did not move (enough), so microphone positions cannot be "
           "separated from the start offsets; move the source around the array";
      throw UnobservableError(s.str());
    }
  }
}

// Mirror the solution so that the gauge signs hold (every mirror leaves the cost unchanged).
Eigen::Vector3d GaugeSigns(const State& s, int D, int gx, int gp, int gz) {
  Eigen::Vector3d sign(1, 1, 1);
  auto mic = [&](int g) { return Eigen::Vector3d(s.mics[3 * (g - 1)], s.mics[3 * (g - 1) + 1], s.mics[3 * (g - 1) + 2]); };
  if (mic(gx).x() < 0) {
    sign.x() = -1;
    sign.y() = -1;  // rotation by pi about z
  }
  if (mic(gp).y() * sign.y() < 0) {
    sign.y() = -sign.y();
    if (D == 3) sign.z() = -sign.z();  // rotation by pi about x
  }
  if (D == 3 && mic(gz).z() * sign.z() < 0) sign.z() = -sign.z();  // mirror z
  return sign;
}

}  // namespace

double ClockStdAt(const CalibrationResult& r, double t) {
  double worst = 0;
  for (const auto& c : r.clock_cov) {
    worst = std::max(worst, std::sqrt(std::max(0.0, c(0, 0) + 2 * t * c(0, 1) + t * t * c(1, 1))));
  }
  return worst;
}

void SolverOptions::Validate(common::Validator& check) const {
  check.That(static_source_prior_xy_m.empty() || static_source_prior_xy_m.size() == 2,
             "static_source_prior_xy_m", "must be empty or [x, y]");
  check.That(gauge_x_mic >= 0 && gauge_plane_mic >= 0 && gauge_z_mic >= 0, "gauge_*_mic",
             "must be >= 0");
}

void ChooseGauge(int num_mics, int dim, const std::vector<Eigen::Vector3d>& nominal, int* x_mic,
                 int* plane_mic, int* z_mic) {
  const int N = num_mics;
  if (static_cast<int>(nominal.size()) != N) {
    if (*x_mic <= 0) *x_mic = 2;
    if (*plane_mic <= 0) *plane_mic = std::min(3, N);
    if (*z_mic <= 0) *z_mic = std::min(4, N);
    return;
  }
  const Eigen::Vector3d o = nominal[0];
  // The lowest-numbered mic scoring at least half the best (the thesis' habit of using low
  // mic numbers), so that well-separated mics define the axes.
  auto best = [&](auto score, std::initializer_list<int> exclude) {
    double s_best = 0;
    for (int n = 1; n < N; ++n) {
      if (std::find(exclude.begin(), exclude.end(), n + 1) != exclude.end()) continue;
      s_best = std::max(s_best, score(nominal[n] - o));
    }
    for (int n = 1; n < N; ++n) {
      if (std::find(exclude.begin(), exclude.end(), n + 1) != exclude.end()) continue;
      if (score(nominal[n] - o) >= 0.5 * s_best && s_best > 0) return n + 1;
    }
    return 0;
  };
  Eigen::Vector3d proj(1, 1, dim == 3 ? 1 : 0);
  if (*x_mic <= 0) *x_mic = best([&](const Eigen::Vector3d& p) { return p.cwiseProduct(proj).norm(); }, {});
  const Eigen::Vector3d ex = (nominal[*x_mic - 1] - o).cwiseProduct(proj).normalized();
  if (*plane_mic <= 0) {
    *plane_mic = best([&](const Eigen::Vector3d& p) {
      const Eigen::Vector3d q = p.cwiseProduct(proj);
      return (q - q.dot(ex) * ex).norm();
    }, {*x_mic});
  }
  if (dim == 3 && *z_mic <= 0) {
    const Eigen::Vector3d ep = nominal[*plane_mic - 1] - o;
    const Eigen::Vector3d normal = ex.cross(ep).normalized();
    *z_mic = best([&](const Eigen::Vector3d& p) { return std::abs(p.dot(normal)); },
                  {*x_mic, *plane_mic});
  }
  if (*z_mic <= 0) *z_mic = std::min(4, N);
}

GaugeTransform GaugeFrameOf(const std::vector<Eigen::Vector3d>& p, int dim, int x_mic,
                            int plane_mic, int z_mic) {
  GaugeTransform g;
  g.origin = p[0];
  if (dim == 2) {
    Eigen::Vector2d e1 = (p[x_mic - 1] - p[0]).head<2>().normalized();
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    r(0, 0) = e1.x();
    r(0, 1) = e1.y();
    r(1, 0) = -e1.y();
    r(1, 1) = e1.x();
    if ((r * (p[plane_mic - 1] - p[0])).y() < 0) r.row(1) *= -1;
    g.rotation = r;
    return g;
  }
  const Eigen::Vector3d e1 = (p[x_mic - 1] - p[0]).normalized();
  Eigen::Vector3d v = p[plane_mic - 1] - p[0];
  v -= v.dot(e1) * e1;
  const Eigen::Vector3d e2 = v.normalized();
  Eigen::Matrix3d r;
  r.row(0) = e1.transpose();
  r.row(1) = e2.transpose();
  r.row(2) = e1.cross(e2).transpose();
  if ((r * (p[z_mic - 1] - p[0])).z() < 0) r.row(2) *= -1;
  g.rotation = r;
  return g;
}

std::vector<Eigen::Vector3d> ToGaugeFrame(const std::vector<Eigen::Vector3d>& positions, int dim,
                                          int x_mic, int plane_mic, int z_mic) {
  const GaugeTransform g = GaugeFrameOf(positions, dim, x_mic, plane_mic, z_mic);
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : positions) out.push_back(g.Apply(p));
  return out;
}

namespace {

void ApplyGuess(const TdoaData& data, const SolverOptions& o, const InitialGuess& g,
                State* state) {
  const int N = data.num_mics, K = data.num_emissions();
  if (static_cast<int>(g.mic_positions_m.size()) == N && !IsLinear(o)) {
    for (int n = 0; n < N; ++n)
      for (int i = 0; i < o.dim(); ++i) state->mics[3 * n + i] = g.mic_positions_m[n][i] - g.mic_positions_m[0][i];
  }
  if (static_cast<int>(g.start_offsets_s.size()) == N && !o.synchronous) {
    for (int n = 1; n < N; ++n) state->clocks[2 * n] = g.start_offsets_s[n] * kMsPerS;
  }
  if (static_cast<int>(g.clock_drift.size()) == N && !o.synchronous && o.estimate_drift) {
    for (int n = 1; n < N; ++n) state->clocks[2 * n + 1] = g.clock_drift[n] * kPpm;
  }
  if (static_cast<int>(g.source_positions_m.size()) == K && !IsLinear(o)) {
    for (int k = 0; k < K; ++k)
      for (int i = 0; i < o.dim(); ++i) state->sources[3 * k + i] = g.source_positions_m[k][i];
  }
  if (static_cast<int>(g.source_angles_rad.size()) == K && IsLinear(o)) {
    for (int k = 0; k < K; ++k) state->sources[k] = g.source_angles_rad[k];
  }
}

}  // namespace

void SetResidualStatistics(CalibrationResult* result) {
  double s1 = 0, s2 = 0, count = 0, max_abs = 0;
  const Eigen::MatrixXd& r = result->tdoa_residual_s;
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    const double v = r.data()[i];
    if (!std::isfinite(v)) continue;
    s1 += v;
    s2 += v * v;
    count += 1;
    max_abs = std::max(max_abs, std::abs(v));
  }
  const double n = std::max(count, 1.0), mean = s1 / n;
  result->residual_rms_s = std::sqrt(s2 / n);
  result->residual_std_s = std::sqrt(std::max(0.0, s2 / n - mean * mean));
  result->residual_max_abs_s = max_abs;
}

CalibrationResult Calibrate(const TdoaData& data, const SolverOptions& options,
                            const InitialGuess* guess) {
  common::ValidateOptions(options);
  const int N = data.num_mics, K = data.num_emissions();
  const SolverOptions& o = options;
  const int D = o.dim();
  const bool linear = IsLinear(o);
  if (N < 2) throw std::invalid_argument("need at least 2 microphones, got " + std::to_string(N));
  if (data.tdoa_s.cols() != N - 1) {
    throw std::invalid_argument("TDOA table has " + std::to_string(data.tdoa_s.cols()) +
                                " columns, expected N-1 = " + std::to_string(N - 1));
  }
  if (static_cast<int>(data.times_s.size()) != K) {
    throw std::invalid_argument("times_s has " + std::to_string(data.times_s.size()) +
                                " entries for " + std::to_string(K) + " emissions");
  }
  for (double t : data.times_s) {
    if (!std::isfinite(t)) throw UnobservableError("an emission time is NaN/inf");
  }
  if (!data.sigma_s.empty()) {
    if (static_cast<int>(data.sigma_s.size()) != K) throw std::invalid_argument("sigma_s size != K");
    for (double s : data.sigma_s) {
      if (!(std::isfinite(s) && s > 0)) throw std::invalid_argument("a TDOA sigma is not > 0");
    }
  }
  if (K < 2) {
    throw UnobservableError("too few emissions: " + std::to_string(K) +
                            " source position(s) cannot determine an array");
  }

  if (o.height_prior_sigma_m > 0 && D == 3 && static_cast<int>(o.mic_heights_m.size()) != N) {
    throw std::invalid_argument("height_prior_sigma_m > 0 needs mic_heights_m with " +
                                std::to_string(N) + " entries");
  }
  if (o.known_positions && !linear &&
      (!guess || static_cast<int>(guess->mic_positions_m.size()) != N)) {
    throw std::invalid_argument("known_positions needs the " + std::to_string(N) +
                                " microphone positions (--nominal)");
  }
  CalibrationResult result;
  result.dim = linear ? 1 : D;
  CheckObservability(data, o, &result.warnings);
  int gx = o.gauge_x_mic, gp = o.gauge_plane_mic, gz = o.gauge_z_mic;
  ChooseGauge(N, D, {}, &gx, &gp, &gz);
  if (!linear) {
    const bool bad = gx < 2 || gx > N || gp < 2 || gp > N || gp == gx ||
                     (D == 3 && (gz < 2 || gz > N || gz == gx || gz == gp));
    if (bad) {
      throw std::invalid_argument("gauge microphones must be distinct, in 2.." + std::to_string(N) +
                                  " (x=" + std::to_string(gx) + " plane=" + std::to_string(gp) +
                                  " z=" + std::to_string(gz) + ")");
    }
  }
  result.gauge_x = gx;
  result.gauge_plane = gp;
  result.gauge_z = D == 3 ? gz : 0;

  // Multi-start: random positions, clocks from a line fit; the best final cost wins.
  std::mt19937_64 rng(o.seed);
  State best;
  double best_cost = std::numeric_limits<double>::infinity();
  const auto t0 = std::chrono::steady_clock::now();
  ceres::Solver::Options sopt;
  sopt.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  sopt.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  sopt.max_num_iterations = o.max_iterations;
  sopt.parameter_tolerance = o.parameter_tolerance;
  sopt.function_tolerance = o.function_tolerance;
  sopt.num_threads = o.num_threads;
  sopt.logging_type = ceres::SILENT;
  for (int s = 0; s < o.num_starts; ++s) {
    State state;
    RandomInitialise(data, o, gx, gp, &rng, &state);
    if (s == 0 && guess) ApplyGuess(data, o, *guess, &state);
    if (!linear && D == 3 && o.height_prior_sigma_m > 0) {
      for (int n = 1; n < N; ++n) {
        if (n != gx - 1 && n != gp - 1) state.mics[3 * n + 2] = o.mic_heights_m[n];
      }
    }
    if (s > 0 && guess && o.known_positions && !linear) {
      InitialGuess positions_only;
      positions_only.mic_positions_m = guess->mic_positions_m;
      ApplyGuess(data, o, positions_only, &state);
    }
    Problem p = Build(data, o, gx, gp, &state, true);
    ceres::Solver::Summary summary;
    ceres::Solve(sopt, p.problem.get(), &summary);
    const StartSummary ss = SummariseStart(s, summary);
    result.total_iterations += ss.iterations;
    result.starts.push_back(ss);
    if (o.verbose) {
      fprintf(stderr, "  start %d/%d: cost %.6g, %d iterations, normalised rms %.3f%s\n", s + 1,
              o.num_starts, ss.final_cost, ss.iterations, ss.normalised_rms,
              ss.converged ? "" : " (not converged)");
    }
    const bool agrees = std::isfinite(best_cost) && std::abs(summary.final_cost - best_cost) <=
                        o.agree_tolerance * std::max(best_cost, 1e-12);
    if (std::isfinite(summary.final_cost) && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best = state;
      result.best_start = s;
      result.iterations = ss.iterations;
    }
    if (agrees && summary.IsSolutionUsable()) break;  // the lowest minimum found twice
  }
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result.recording_end_s = *std::max_element(data.times_s.begin(), data.times_s.end());
  if (!std::isfinite(best_cost)) throw std::runtime_error("no start produced a finite cost");
  result.final_cost = best_cost;

  // Gauge signs by mirroring everything.
  Eigen::Vector3d sign(1, 1, 1);
  if (!linear && !o.known_positions) {
    sign = GaugeSigns(best, D, gx, gp, gz);
    for (int n = 0; n < N; ++n)
      for (int i = 0; i < 3; ++i) best.mics[3 * n + i] *= sign[i];
    for (int k = 0; k < K; ++k)
      for (int i = 0; i < 3; ++i) best.sources[3 * k + i] *= sign[i];
  }

  // Estimates in SI units.
  result.mic_positions_m.resize(N);
  result.start_offsets_s.assign(N, 0.0);
  result.clock_drift.assign(N, 0.0);
  for (int n = 0; n < N; ++n) {
    result.mic_positions_m[n] = Eigen::Vector3d(best.mics[3 * n], best.mics[3 * n + 1],
                                                best.mics[3 * n + 2]);
    if (n > 0 && !o.synchronous) {
      result.start_offsets_s[n] = best.clocks[2 * n] / kMsPerS;
      result.clock_drift[n] = best.clocks[2 * n + 1] / kPpm;
    }
  }
  for (int k = 0; k < K; ++k) {
    if (linear) {
      result.source_angles_rad.push_back(best.sources[k]);
    } else {
      result.source_positions_m.emplace_back(best.sources[3 * k], best.sources[3 * k + 1],
                                             best.sources[3 * k + 2]);
    }
  }

  // Residuals without the robust loss, in seconds.
  result.tdoa_residual_s = Eigen::MatrixXd::Constant(K, N - 1, std::nan(""));
  for (int k = 0; k < K; ++k) {
    for (int n = 1; n < N; ++n) {
      const double z = data.tdoa_s(k, n - 1);
      if (!std::isfinite(z)) continue;
      double pred;
      if (linear) {
        pred = -LinearMicX(o, n) * std::cos(result.source_angles_rad[k]) / o.speed_of_sound_mps;
      } else {
        const Eigen::Vector3d& s = result.source_positions_m[k];
        pred = ((result.mic_positions_m[n] - s).norm() - s.norm()) / o.speed_of_sound_mps;
      }
      pred += result.start_offsets_s[n] + data.times_s[k] * result.clock_drift[n];
      result.tdoa_residual_s(k, n - 1) = pred - z;
    }
  }
  SetResidualStatistics(&result);
  AssessSolve(data, o, &result);
  const double f = result.variance_factor;

  // Marginal covariances at the solution (robust loss applied, as in the solve), scaled by the
  // variance factor.
  result.mic_position_cov.assign(N, Eigen::Matrix3d::Zero());
  result.clock_cov.assign(N, Eigen::Matrix2d::Zero());
  result.source_cov.assign(K, Eigen::Matrix3d::Zero());
  if (o.compute_covariance) {
    const auto tc = std::chrono::steady_clock::now();
    State state = best;
    Problem p = Build(data, o, gx, gp, &state, true);
    ceres::Covariance cov(CovarianceOptions(o.num_threads));
    std::vector<std::pair<const double*, const double*>> blocks;
    const int src_stride = linear ? 1 : 3;
    for (int n = 1; n < N; ++n) {
      if (!linear && !o.known_positions && p.problem->HasParameterBlock(&state.mics[3 * n]))
        blocks.emplace_back(&state.mics[3 * n], &state.mics[3 * n]);
      if (!o.synchronous && p.problem->HasParameterBlock(&state.clocks[2 * n]))
        blocks.emplace_back(&state.clocks[2 * n], &state.clocks[2 * n]);
    }
    for (int k = 0; k < K; ++k) {
      blocks.emplace_back(&state.sources[src_stride * k], &state.sources[src_stride * k]);
    }
    if (!cov.Compute(blocks, p.problem.get())) {
      throw UnobservableError(
          "the Jacobian at the solution is rank deficient (Ceres covariance failed): some "
          "microphone positions, offsets or drifts are not determined by these TDOAs "
          "(source motion too small or too few positions for the unknowns), or the gauge "
          "microphones (x " + std::to_string(gx) + ", plane " + std::to_string(gp) +
          (D == 3 ? ", z " + std::to_string(gz) : std::string()) +
          ") are collinear/coplanar with mic 1 and cannot fix the frame: choose others with "
          "solver.gauge_*_mic or give --nominal");
    }
    const int pd = linear ? 0 : D;
    std::ostringstream bad;
    for (int n = 1; n < N; ++n) {
      if (!linear && !o.known_positions && p.problem->HasParameterBlock(&state.mics[3 * n])) {
        Eigen::Matrix<double, 3, 3, Eigen::RowMajor> c = Eigen::Matrix3d::Zero();
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(pd, pd);
        cov.GetCovarianceBlock(&state.mics[3 * n], &state.mics[3 * n], m.data());
        c.topLeftCorner(pd, pd) = f * m;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) c(i, j) *= sign[i] * sign[j];
        result.mic_position_cov[n] = c;
        const double std_m = std::sqrt(std::max(0.0, c.trace()));
        if (!(std_m <= o.max_position_std_m)) {
          bad << MicName(n) << " position std " << std_m << " m; ";
        }
      }
      if (!o.synchronous && p.problem->HasParameterBlock(&state.clocks[2 * n])) {
        Eigen::Matrix<double, 2, 2, Eigen::RowMajor> m;
        cov.GetCovarianceBlock(&state.clocks[2 * n], &state.clocks[2 * n], m.data());
        Eigen::Matrix2d scale = Eigen::Vector2d(1 / kMsPerS, 1 / kPpm).asDiagonal();
        result.clock_cov[n] = f * scale * m * scale;
        const double std_tau = std::sqrt(std::max(0.0, result.clock_cov[n](0, 0)));
        if (!(std_tau <= o.max_offset_std_s)) {
          bad << MicName(n) << " start-offset std " << std_tau * 1e3 << " ms; ";
        }
      }
    }
    for (int k = 0; k < K; ++k) {
      if (linear) {
        double v;
        cov.GetCovarianceBlock(&state.sources[k], &state.sources[k], &v);
        result.source_cov[k](0, 0) = f * v;
      } else {
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(D, D);
        cov.GetCovarianceBlock(&state.sources[3 * k], &state.sources[3 * k], m.data());
        Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
        c.topLeftCorner(D, D) = f * m;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) c(i, j) *= sign[i] * sign[j];
        result.source_cov[k] = c;
      }
    }
    result.has_covariance = true;
    result.covariance_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - tc).count();
    if (!bad.str().empty()) {
      throw UnobservableError(
          "calibration too uncertain to use: " + bad.str() +
          "(the data do not constrain these: more source positions spread around and through "
          "the array are needed; or the gauge microphones (x " + std::to_string(gx) +
          ", plane " + std::to_string(gp) + (D == 3 ? ", z " + std::to_string(gz) : std::string()) +
          ") are (nearly) collinear/coplanar with mic 1 and do not fix the frame)");
    }
  }
  return result;
}

void AssessSolve(const TdoaData& data, const SolverOptions& o, CalibrationResult* r) {
  if (r->starts.empty()) return;
  const StartSummary* best = &r->starts.front();
  for (const auto& s : r->starts) {
    if (s.start == r->best_start) best = &s;
  }
  r->converged = best->converged;
  if (!r->converged) {
    r->warnings.push_back(
        "the solve did not converge: the best start (" + std::to_string(r->best_start + 1) +
        ") stopped after " + std::to_string(best->iterations) +
        " iterations (solver.max_iterations " + std::to_string(o.max_iterations) +
        ") without meeting the tolerances; the positions, offsets and drifts and their std are "
        "where it stopped, not a solution, and not to be trusted");
  }
  double sum = 0;
  int m = 0;
  for (int k = 0; k < r->tdoa_residual_s.rows(); ++k) {
    const double sigma = data.sigma_s.empty() ? o.tdoa_sigma_s : data.sigma_s[k];
    for (int n = 0; n < r->tdoa_residual_s.cols(); ++n) {
      const double e = r->tdoa_residual_s(k, n);
      if (!std::isfinite(e)) continue;
      sum += (e / sigma) * (e / sigma);
      ++m;
    }
  }
  // Degrees of freedom as Ceres counts them (priors, e.g. on free array poses, included).
  const int dof = std::max(m, best->num_residuals) - best->num_parameters;
  r->variance_factor = dof > 0 ? std::max(1.0, sum / dof) : 1.0;
}

namespace internal_testing {

template <int D>
bool CheckTdoaJacobianD() {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  TdoaCost<D> analytic(0.012, 37.5, 3e-4, 340);
  ceres::AutoDiffCostFunction<TdoaResidual<D>, 1, D, 2, D> autodiff(
      new TdoaResidual<D>(0.012, 37.5, 3e-4, 340));
  for (int trial = 0; trial < 20; ++trial) {
    double mic[3], clock[2] = {u(rng) * 50, u(rng) * 60}, src[3];
    for (int i = 0; i < 3; ++i) {
      mic[i] = u(rng);
      src[i] = u(rng);
    }
    const double* params[3] = {mic, clock, src};
    double ra, rb, ja[3][3], jb[3][3];
    double* jpa[3] = {ja[0], ja[1], ja[2]};
    double* jpb[3] = {jb[0], jb[1], jb[2]};
    analytic.Evaluate(params, &ra, jpa);
    autodiff.Evaluate(params, &rb, jpb);
    if (std::abs(ra - rb) > 1e-9 * std::max(1.0, std::abs(ra))) return false;
    const int sizes[3] = {D, 2, D};
    for (int b = 0; b < 3; ++b)
      for (int i = 0; i < sizes[b]; ++i)
        if (std::abs(ja[b][i] - jb[b][i]) > 1e-9 * std::max(1.0, std::abs(jb[b][i]))) return false;
  }
  return true;
}

bool CheckTdoaJacobian(int dim) { return dim == 3 ? CheckTdoaJacobianD<3>() : CheckTdoaJacobianD<2>(); }

}  // namespace internal_testing

}  // namespace mic_calibrate
}  // namespace sarmap
