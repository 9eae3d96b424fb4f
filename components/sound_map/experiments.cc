#include "sound_map/experiments.h"

#include <chrono>
#include <cmath>

#include "sound_map/idp_ekf.h"
#include "sound_map/joint_optimizer.h"

namespace sarmap {
namespace sound_map {

namespace {
double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

const char* MethodName(Method m) {
  switch (m) {
    case Method::kEkfOdometry: return "ekf-idp-odometry";
    case Method::kJointOdometry: return "joint-ls-odometry";
    case Method::kCiSubmaps: return "ci-submaps";
    case Method::kFullEkf: return "full-ekf";
    case Method::kJoint: return "joint-ls";
  }
  return "?";
}

SourceScore ScoreSources(const std::vector<Eigen::Vector3d>& est, const std::vector<bool>& heard,
                         const std::vector<Eigen::Vector3d>& truth, bool three_d, double converged_error_m) {
  SourceScore s;
  double sum2 = 0;
  int converged = 0;
  for (size_t j = 0; j < truth.size(); ++j) {
    if (!heard[j]) continue;
    Eigen::Vector3d e = est[j] - truth[j];
    if (!three_d) e.z() = 0;
    const double err = std::isfinite(e.norm()) ? e.norm() : 1e9;
    s.errors_m.push_back(err);
    sum2 += err * err;
    converged += err < converged_error_m;
    ++s.num_sources;
  }
  if (s.num_sources > 0) {
    s.rms_m = std::sqrt(sum2 / s.num_sources);
    s.convergence_rate = static_cast<double>(converged) / s.num_sources;
  }
  return s;
}

RunResult RunMethod(const Sim2dData& d, Method method, const RunOptions& ro) {
  RunResult out;
  const bool three_d = d.config.three_d;
  const size_t ns = d.sources.size();
  std::vector<Eigen::Vector3d> est(ns, Eigen::Vector3d::Zero());
  std::vector<bool> heard(ns, false);
  out.covariances.assign(ns, Eigen::Matrix3d::Zero());
  const double t0 = Now();

  if (method == Method::kJointOdometry || method == Method::kJoint) {
    JointProblem2d p = JointProblemFromSimulation(d, method == Method::kJoint);
    if (method == Method::kJoint) {
      // Poses from odometry + landmarks first, then sources triangulated from them, then
      // everything jointly (dead reckoning with 5 deg per step is no initial guess).
      p.use_sound_edges = false;
      SolveJoint(&p);
      p.use_sound_edges = true;
      TriangulateSources(&p);
    }
    SolveJoint(&p);
    est = p.sources;
    heard = p.source_observed;
  } else {
    IdpEkf::Options eo;
    eo.three_d = three_d;
    eo.mount = d.mount;
    eo.initial_inverse_depth = ro.initial_inverse_depth;
    eo.inverse_depth_sigma = ro.inverse_depth_sigma;
    const bool use_landmarks = method != Method::kEkfOdometry;
    const bool ci = method == Method::kCiSubmaps;
    IdpEkf main(eo);   // full / odometry-only EKF, or the CI localisation map
    IdpEkf sound(eo);  // CI sound map
    main.Reset(d.truth[0], Eigen::Matrix3d::Zero());
    sound.Reset(d.truth[0], Eigen::Matrix3d::Zero());
    const Eigen::Matrix3d q = d.odometry_covariance();
    const Eigen::Matrix2d r_lm = Eigen::Vector2d(d.config.landmark_sigma_m * d.config.landmark_sigma_m,
                                                 d.config.landmark_sigma_rad * d.config.landmark_sigma_rad)
                                     .asDiagonal();
    const int m = three_d ? 2 : 1;
    const Eigen::MatrixXd r_snd = Eigen::MatrixXd::Identity(m, m) * d.config.sound_sigma_rad * d.config.sound_sigma_rad;
    double step_sum = 0, step_max = 0;
    int steps = 0;
    for (size_t k = 0; k < d.truth.size(); ++k) {
      if (k > 0) main.Predict(d.odometry[k], q);
      if (use_landmarks) {
        for (const auto& o : d.landmark_obs[k]) {
          if (!main.HasLandmark(o.id))
            main.AddLandmark(o.id, o.z, r_lm);
          else
            main.UpdateLandmark(o.id, o.z, r_lm);
        }
      }
      IdpEkf& sm = ci ? sound : main;
      const double s0 = Now();
      if (ci) {
        // The localisation map keeps the poses sources are first heard from; then the
        // sound map takes [current, anchors] from it (back-propagation, 4.20-4.25).
        bool new_source = false;
        for (const auto& o : d.sound_obs[k]) new_source = new_source || !sound.HasSource(o.source);
        if (new_source) main.AddAnchor(static_cast<int64_t>(k));
        Pose2 cur;
        std::vector<std::pair<int64_t, Pose2>> anchors;
        Eigen::MatrixXd cov;
        main.SharedState(sound.anchor_ids(), &cur, &anchors, &cov);
        sound.BackPropagate(cur, anchors, cov);
      }
      for (const auto& o : d.sound_obs[k]) {
        if (!sm.HasSource(o.source))
          sm.AddSource(o.source, static_cast<int64_t>(k), o.z, r_snd);
        else
          sm.UpdateSource(o.source, o.z, r_snd, ro.gate_chi2);
      }
      const double dt = (Now() - s0) * 1e3;
      if (!d.sound_obs[k].empty() || ci) {
        step_sum += dt;
        step_max = std::max(step_max, dt);
        ++steps;
      }
    }
    IdpEkf& sm = ci ? sound : main;
    for (int64_t id : sm.source_ids()) {
      Eigen::Matrix3d c;
      sm.SourcePoint(id, &est[id], &c);
      out.covariances[id] = c;
      heard[id] = true;
    }
    out.sound_step_ms_mean = steps ? step_sum / steps : 0;
    out.sound_step_ms_max = step_max;
  }
  out.total_seconds = Now() - t0;
  out.estimates = est;
  out.score = ScoreSources(est, heard, d.sources, three_d, ro.converged_error_m);
  return out;
}

}  // namespace sound_map
}  // namespace sarmap
