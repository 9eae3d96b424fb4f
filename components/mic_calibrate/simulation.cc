#include "mic_calibrate/simulation.h"

#include <cmath>
#include <random>
#include <cstdlib>

#include <Eigen/Geometry>

namespace sarmap {
namespace mic_calibrate {

SimData Simulate(const SimScenario& sc, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  SimData sim;
  int N;
  if (sc.linear) {
    N = sc.linear_mics;
    for (int n = 0; n < N; ++n) sim.mic_positions_m.emplace_back(n * sc.spacing_m, 0, 0);
  } else {
    N = sc.cols * sc.rows * sc.layers;
    for (int l = 0; l < sc.layers; ++l)
      for (int r = 0; r < sc.rows; ++r)
        for (int c = 0; c < sc.cols; ++c)
          sim.mic_positions_m.emplace_back(c * sc.spacing_m, r * sc.spacing_m,
                                           l * sc.layer_spacing_m);
    // Thesis gauge: the last mic of the first row on +x, the first mic of the second row has
    // y > 0, (3D) the first mic of the third row keeps z = 0, the first mic of layer 2 z > 0.
    sim.gauge_x = sc.cols;
    if (sc.layers > 1) {
      sim.gauge_plane = std::min(2, sc.rows - 1) * sc.cols + 1;
      sim.gauge_z = sc.rows * sc.cols + 1;
    } else {
      sim.gauge_plane = sc.cols + 1;
    }
  }
  sim.start_offsets_s.assign(N, 0.0);
  sim.clock_drift.assign(N, 0.0);
  for (int n = 1; n < N; ++n) {
    sim.start_offsets_s[n] = (2 * uni(rng) - 1) * sc.max_offset_s;
    sim.clock_drift[n] = (2 * uni(rng) - 1) * sc.max_drift;
  }
  const int K = sc.num_positions;
  const bool is3d = !sc.linear && sc.layers > 1;
  // Source path.
  if (sc.linear) {
    double beta = M_PI * (0.1 + 0.8 * uni(rng)), dir = uni(rng) < 0.5 ? -1 : 1;
    for (int k = 0; k < K; ++k) {
      sim.source_angles_rad.push_back(beta);
      if (beta + dir * sc.angle_step_rad > M_PI || beta + dir * sc.angle_step_rad < 0) dir = -dir;
      beta += dir * sc.angle_step_rad;
    }
  } else if (sc.path == "loop") {
    const Eigen::Vector3d centre(0.5 * (sc.cols - 1) * sc.spacing_m,
                                 0.5 * (sc.rows - 1) * sc.spacing_m,
                                 is3d ? 0.5 * (sc.z_min_m + sc.z_max_m) : 0.0);
    const double r0 = std::hypot(centre.x(), centre.y()) + sc.loop_clearance_m;
    const double phase = 2 * M_PI * uni(rng), dir = uni(rng) < 0.5 ? -1 : 1;
    const double zphase = 2 * M_PI * uni(rng);
    double theta = 2 * M_PI * uni(rng);
    for (int k = 0; k < K; ++k) {
      const double r = r0 * (1 + sc.loop_wobble * std::sin(sc.loop_lobes * theta + phase));
      Eigen::Vector3d s = centre + Eigen::Vector3d(r * std::cos(theta), r * std::sin(theta), 0);
      if (is3d) s.z() = centre.z() + 0.5 * (sc.z_max_m - sc.z_min_m) * std::sin(1.5 * theta + zphase);
      sim.source_positions_m.push_back(s);
      theta += dir * sc.step_m / r;
    }
  } else {
    Eigen::Vector3d lo(-sc.margin_m, -sc.margin_m, is3d ? sc.z_min_m : 0);
    Eigen::Vector3d hi((sc.cols - 1) * sc.spacing_m + sc.margin_m,
                       (sc.rows - 1) * sc.spacing_m + sc.margin_m, is3d ? sc.z_max_m : 0);
    Eigen::Vector3d s;
    for (int i = 0; i < 3; ++i) s[i] = lo[i] + (hi[i] - lo[i]) * uni(rng);
    Eigen::Vector3d dir(gauss(rng), gauss(rng), is3d ? gauss(rng) : 0);
    dir.normalize();
    for (int k = 0; k < K; ++k) {
      sim.source_positions_m.push_back(s);
      Eigen::Vector3d turn(gauss(rng), gauss(rng), is3d ? gauss(rng) : 0);
      dir = (dir + sc.heading_sigma_rad * turn).normalized();
      Eigen::Vector3d next = s + sc.step_m * dir;
      for (int i = 0; i < 3; ++i) {
        if (next[i] < lo[i] || next[i] > hi[i]) {
          dir[i] = -dir[i];
          next[i] = s[i] + sc.step_m * dir[i];
        }
      }
      s = next;
    }
  }
  // TDOAs: z_n(k) = geometric + tau_n + t_k delta_n + noise, quantised to samples.
  TdoaData& d = sim.data;
  d.num_mics = N;
  d.tdoa_s.resize(K, N - 1);
  for (int k = 0; k < K; ++k) {
    const double t = (k + 1) * sc.dt_s;  // t_k = k * dt, k = 1..K
    d.times_s.push_back(t);
    for (int n = 1; n < N; ++n) {
      double geo;
      if (sc.linear) {
        geo = -sim.mic_positions_m[n].x() * std::cos(sim.source_angles_rad[k]) /
              sc.speed_of_sound_mps;
      } else {
        const Eigen::Vector3d& s = sim.source_positions_m[k];
        geo = ((sim.mic_positions_m[n] - s).norm() - (sim.mic_positions_m[0] - s).norm()) /
              sc.speed_of_sound_mps;
      }
      double z = geo + sim.start_offsets_s[n] + t * sim.clock_drift[n] +
                 sc.tdoa_sigma_s / sc.noise_conservative_factor * gauss(rng);
      if (sc.sample_rate_hz > 0) z = std::round(z * sc.sample_rate_hz) / sc.sample_rate_hz;
      d.tdoa_s(k, n - 1) = z;
    }
  }
  return sim;
}

SolverOptions SolverOptionsFor(const SimScenario& sc, const SimData& sim) {
  SolverOptions o;
  o.speed_of_sound_mps = sc.speed_of_sound_mps;
  o.tdoa_sigma_s = sc.tdoa_sigma_s;
  if (sc.linear) {
    o.geometry = "linear";
    o.linear_spacing_m = sc.spacing_m;
    o.random_walk_sigma_rad = sc.random_walk_sigma_rad;
    o.max_iterations = 20;                          // Table 3.4
  } else {
    o.geometry = sc.layers > 1 ? "3d" : "planar";
    o.random_walk_sigma_m = sc.random_walk_sigma_m;
    o.max_iterations = 50;          // Table 3.1
    o.gauge_x_mic = sim.gauge_x;
    o.gauge_plane_mic = sim.gauge_plane;
    o.gauge_z_mic = sim.gauge_z;
    o.init_extent_m = std::max((sc.cols - 1) * sc.spacing_m, (sc.rows - 1) * sc.spacing_m) +
                      sc.margin_m;
  }
  return o;
}

Errors CompareToTruth(const CalibrationResult& r, const SimData& sim) {
  Errors e;
  const int N = static_cast<int>(sim.mic_positions_m.size());
  double sp = 0, so = 0, sd = 0;
  for (int n = 1; n < N; ++n) {
    sp += (r.mic_positions_m[n] - sim.mic_positions_m[n]).squaredNorm();
    so += std::pow(r.start_offsets_s[n] - sim.start_offsets_s[n], 2);
    sd += std::pow(r.clock_drift[n] - sim.clock_drift[n], 2);
  }
  e.position_rms_m = std::sqrt(sp / (N - 1));
  const int dim = r.dim == 3 ? 3 : 2;
  e.position_rms_per_coordinate_m = std::sqrt(sp / (N * dim));
  e.offset_rms_s = std::sqrt(so / (N - 1));
  e.drift_rms = std::sqrt(sd / (N - 1));
  return e;
}

MonteCarloSummary RunMonteCarlo(const SimScenario& sc, int runs, uint64_t first_seed,
                                void (*configure)(SolverOptions*)) {
  MonteCarloSummary m;
  for (int i = 0; i < runs; ++i) {
    const SimData sim = Simulate(sc, first_seed + i);
    SolverOptions o = SolverOptionsFor(sc, sim);
    o.seed = static_cast<int64_t>(1000 + first_seed + i);
    if (configure) configure(&o);
    ++m.runs;
    try {
      const CalibrationResult r = Calibrate(sim.data, o);
      const Errors e = CompareToTruth(r, sim);
      m.mean.position_rms_m += e.position_rms_m;
      m.mean.position_rms_per_coordinate_m += e.position_rms_per_coordinate_m;
      m.mean.offset_rms_s += e.offset_rms_s;
      m.mean.drift_rms += e.drift_rms;
      m.mean_solve_time_s += r.solve_time_s;
      m.mean_iterations += r.iterations;
      m.mean_total_iterations += r.total_iterations;
      m.mean_residual_rms_s += r.residual_rms_s;
    } catch (const std::exception& ex) {
      ++m.failures;
      m.failure_messages.push_back(ex.what());
    }
  }
  const int ok = m.runs - m.failures;
  if (ok > 0) {
    m.mean.position_rms_m /= ok;
    m.mean.position_rms_per_coordinate_m /= ok;
    m.mean.offset_rms_s /= ok;
    m.mean.drift_rms /= ok;
    m.mean_solve_time_s /= ok;
    m.mean_iterations /= ok;
    m.mean_total_iterations /= ok;
    m.mean_residual_rms_s /= ok;
  }
  return m;
}

}  // namespace mic_calibrate
}  // namespace sarmap
