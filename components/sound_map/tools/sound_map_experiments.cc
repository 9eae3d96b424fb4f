// sarmap-sound-map-experiments: prints the tables of Su 2017 §4.4.1 (Fig. 4.5, Fig. 4.11)
// and §5.5.1 (Table 5.1, Fig. 5.8) from the simulation harness.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "handheld_sound_map/linear_array.h"
#include "handheld_sound_map/linear_array_map.h"
#include "sound_map/experiments.h"

using namespace sarmap::sound_map;

namespace {

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}
double Std(const std::vector<double>& v) {
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(s / (v.size() - 1)) : 0;
}

void Fig45(int runs) {
  printf("== Fig. 4.5: odometry + sound only, square %.0f m side, %d Monte Carlo runs per cell\n",
         10.0, runs);
  printf("noise_scale odo_sigma_m odo_sigma_deg | method            dim  rms_m(mean) conv_rate\n");
  const std::vector<double> scales = {1, 2, 4, 8, 16, 32, 64};
  for (double s : scales) {
    for (bool three_d : {false, true}) {
      for (Method m : {Method::kEkfOdometry, Method::kJointOdometry}) {
        std::vector<double> rms, conv;
        for (int r = 0; r < runs; ++r) {
          Sim2dConfig c;
          c.three_d = three_d;
          c.odo_sigma_m = 0.001 * s;
          c.odo_sigma_rad = 0.016 * s * M_PI / 180;
          c.seed = 1000 + r;
          const RunResult res = RunMethod(Simulate2d(c), m);
          rms.push_back(res.score.rms_m);
          conv.push_back(res.score.convergence_rate);
        }
        printf("%6.0f      %.4f      %.4f     | %-17s %s   %8.3f   %6.2f\n", s, 0.001 * s,
               0.016 * s, MethodName(m), three_d ? "3D" : "2D", Mean(rms), Mean(conv));
      }
    }
  }
}

void Fig411(int runs) {
  printf(
      "== Fig. 4.11: odometry (0.02 m, 5 deg per 0.2 m step) + range-bearing landmarks, %d runs\n",
      runs);
  printf(
      "length_m | method      rms_mean_m rms_std_m conv_rate  time_s  sound_step_ms(mean/max)\n");
  for (double side : {5.0, 10.0, 20.0, 30.0, 45.0}) {
    for (Method m : {Method::kCiSubmaps, Method::kFullEkf, Method::kJoint}) {
      std::vector<double> rms, conv, t, step, stepmax;
      double length = 0;
      for (int r = 0; r < runs; ++r) {
        const Sim2dData d = Simulate2d(Fig411Config(side, r));
        length = d.length_m();
        const RunResult res = RunMethod(d, m);
        rms.push_back(res.score.rms_m);
        conv.push_back(res.score.convergence_rate);
        t.push_back(res.total_seconds);
        step.push_back(res.sound_step_ms_mean);
        stepmax.push_back(res.sound_step_ms_max);
      }
      printf("%7.1f  | %-11s %8.3f  %8.3f   %6.2f  %7.3f   %.4f / %.4f\n", length, MethodName(m),
             Mean(rms), Std(rms), Mean(conv), Mean(t), Mean(step), Mean(stepmax));
    }
  }
}

// Knobs of the §5.5.1 runs (defaults: the library's defaults).
struct Knobs {
  LinearMapperOptions mapper;
  double noise_scale = 1.0;
  int seed0 = 3000;
  int verbose = 0;
  std::shared_ptr<const DoaSensorModel> doa_generator;  // null: Gaussian 10-20 deg
  double doa_quantum_rad = 0;
  double updown_m = 0.6;
  double landmark_density = -1;
  std::vector<int> variants = {1, 3, 4,
                               2};  // table5.1 rows  // per m^2 (-1: the simulation's default)
  // raw DOA -> corrected angle and variance for the online map (the live localiser's role);
  // null: the raw angle with the simulated noise's sigma.
  std::shared_ptr<const DoaSensorModel> online_sensor_model;
  Eigen::Vector3d axis_sq = Eigen::Vector3d::Zero();  // summed squared error per axis (converged)
  int axis_n = 0;
};
Knobs g_knobs;

LinearRunResult RunTable51(LinearSimConfig c, int r, int num_hypotheses = 0) {
  c.doa_noise_scale = g_knobs.noise_scale;
  c.doa_generator = g_knobs.doa_generator;
  c.doa_quantum_rad = g_knobs.doa_quantum_rad;
  c.seed = g_knobs.seed0 + r;
  LinearMapperOptions o = g_knobs.mapper;
  if (num_hypotheses > 0) o.num_hypotheses = num_hypotheses;
  c.updown_m = g_knobs.updown_m;
  if (g_knobs.landmark_density > 0) c.landmark_density_per_m2 = g_knobs.landmark_density;
  const LinearSimData d = SimulateLinear(c);
  LinearRunResult res = RunLinearArrayMapping(d, o);
  for (size_t j = 0; j < d.sources.size(); ++j)
    if (res.source_converged[j]) {
      g_knobs.axis_sq += (res.estimates[j] - d.sources[j]).cwiseAbs2();
      ++g_knobs.axis_n;
    }
  return res;
}

void Table51(int runs) {
  printf(
      "== Table 5.1 / Figs. 5.6-5.7: linear array, 8 sources, %d runs (thesis RMS 0.1302 m, 0.2688 "
      "m)\n",
      runs);
  printf(
      "rms: sqrt(mean |error|^2) over converged sources, averaged over runs; floor: least squares "
      "from the\n"
      "true poses started at the truth (all heard sources); per source: mean error when converged "
      "(m) / runs converged\n");
  // Variants of trajectory 1 (the thesis' sensor orientation cannot be read back): 1 faces
  // along the path, 3 is turned 80 deg from facing the source on the arcs, 4 keeps facing
  // along the side while side-stepping round the source.
  for (int traj : g_knobs.variants) {
    std::vector<double> rms, conv, ok, floor, pooled, pose_t, pose_r;
    std::vector<double> err_sum(8, 0.0);
    std::vector<int> err_n(8, 0);
    g_knobs.axis_sq.setZero();
    g_knobs.axis_n = 0;
    for (int r = 0; r < runs; ++r) {
      LinearSimConfig c;
      c.trajectory = traj >= 3 ? 1 : traj;
      if (traj == 3) c.arc_face_offset_rad = 80 * M_PI / 180;
      if (traj == 4) c.fixed_heading = true;
      const LinearRunResult res = RunTable51(c, r);
      rms.push_back(res.rms_m);
      conv.push_back(res.convergence_rate);
      ok.push_back(res.correct_convergence_rate);
      floor.push_back(res.floor_rms_m);
      for (size_t j = 0; j < res.errors_m.size() && j < 8; ++j)
        if (!std::isnan(res.errors_m[j])) {
          err_sum[j] += res.errors_m[j];
          ++err_n[j];
          pooled.push_back(res.errors_m[j] * res.errors_m[j]);
        }
      pose_t.push_back(res.pose_rms_m);
      pose_r.push_back(res.pose_rms_rad * 180 / M_PI);
      if (g_knobs.verbose)
        printf("  run %d: rms %.4f conv %.3f floor %.4f\n", r, res.rms_m, res.convergence_rate,
               res.floor_rms_m);
    }
    printf(
        "trajectory %s: rms %.4f m (std %.4f, pooled %.4f), convergence rate %.3f (within 1 m: "
        "%.3f), floor %.4f m\n",
        traj == 1   ? "1 (facing along the path)"
        : traj == 3 ? "1 (arcs: 80 deg off the source)"
        : traj == 4 ? "1 (facing along the side)"
                    : "2",
        Mean(rms), Std(rms), std::sqrt(Mean(pooled)), Mean(conv), Mean(ok), Mean(floor));
    const Eigen::Vector3d axis_rms = (g_knobs.axis_sq / std::max(1, g_knobs.axis_n)).cwiseSqrt();
    printf("   rms per axis x %.3f y %.3f z %.3f;", axis_rms.x(), axis_rms.y(), axis_rms.z());
    printf(" poses rms %.3f m %.2f deg;", Mean(pose_t), Mean(pose_r));
    printf(" per source:");
    for (int j = 0; j < 8; ++j)
      printf(" %.3f/%d", err_n[j] ? err_sum[j] / err_n[j] : NAN, err_n[j]);
    printf("\n");
    fflush(stdout);
  }
}

// Table 5.1 through the online map the hand-held node runs (LinearArraySoundMap): the same
// simulated walks and DOAs, each raw DOA corrected as the live localiser does (the sensor
// model: mean and variance of the true angle given the raw one), with the simulated source as
// the DOA track id; the pose stream is either the true poses (the map's own floor) or a
// dead-reckoned RGB-D odometry of 3 mm / 0.1 deg per 0.2 m step (no landmarks, no loop
// closures: what the hand-held node is given). RMS over the sources converged under their own
// track, averaged over runs, as Table 5.1.
void Table51Online(int runs) {
  printf(
      "== Table 5.1 through the online map (LinearArraySoundMap), 8 sources, %d runs (thesis "
      "RMS 0.1302 m)\n",
      runs);
  for (int traj : g_knobs.variants) {
    for (bool true_poses : {true, false}) {
      std::vector<double> rms, rms_xy, conv;
      for (int r = 0; r < runs; ++r) {
        LinearSimConfig c;
        c.trajectory = traj >= 3 ? 1 : traj;
        if (traj == 3) c.arc_face_offset_rad = 80 * M_PI / 180;
        if (traj == 4) c.fixed_heading = true;
        c.odo_sigma_m = 0.003;
        c.odo_sigma_rad = 0.1 * M_PI / 180;
        c.landmark_density_per_m2 = 0;
        c.doa_noise_scale = g_knobs.noise_scale;
        c.doa_generator = g_knobs.doa_generator;
        c.doa_quantum_rad = g_knobs.doa_quantum_rad;
        c.updown_m = g_knobs.updown_m;
        c.seed = g_knobs.seed0 + r;
        const LinearSimData d = SimulateLinear(c);
        LinearArrayMapOptions o;
        o.hypotheses.num_hypotheses = g_knobs.mapper.num_hypotheses;
        // The pose source's noise per 0.2 m step, as the map is told it.
        o.odometry_sigma_floor_m = true_poses ? 0.0005 : 0.003;
        o.odometry_sigma_m_per_m = 0;
        o.odometry_sigma_floor_deg = true_poses ? 0.01 : 0.1;
        o.odometry_sigma_deg_per_m = 0;
        LinearArraySoundMap map(o);
        Eigen::Isometry3d odom = d.truth[0];
        for (size_t k = 0; k < d.truth.size(); ++k) {
          if (k > 0) odom = odom * d.odometry[k];
          const sarmap::common::Utime t = static_cast<int64_t>(k) * 400000;  // 0.2 m at 0.5 m/s
          map.OnPose(t, true_poses ? d.truth[k] : odom);
          std::vector<LinearArraySoundMap::Doa> doas;
          for (const auto& sound : d.sound_obs[k]) {
            LinearArraySoundMap::Doa doa;
            doa.track_id = sound.source;
            double mean = sound.raw_beta, variance = 0;
            if (g_knobs.online_sensor_model) {
              g_knobs.online_sensor_model->Predict(sound.raw_beta, &mean, &variance);
            } else {
              variance = std::pow(g_knobs.noise_scale * SimulatedDoaSigma(sound.raw_beta), 2);
            }
            doa.beta_rad = mean;
            doa.sigma_rad = std::sqrt(variance);
            doas.push_back(doa);
          }
          map.OnDoa(t, doas);
        }
        map.Finish();
        double sq = 0, sq_xy = 0;
        int converged = 0;
        for (size_t j = 0; j < d.sources.size(); ++j) {
          for (const auto& source : map.sources()) {
            const bool own = std::find(source.track_ids.begin(), source.track_ids.end(),
                                       static_cast<int64_t>(j)) != source.track_ids.end();
            if (!own || !source.converged) continue;
            sq += (source.position_m - d.sources[j]).squaredNorm();
            sq_xy += (source.position_m - d.sources[j]).head<2>().squaredNorm();
            ++converged;
            break;
          }
        }
        if (converged > 0) {
          rms.push_back(std::sqrt(sq / converged));
          rms_xy.push_back(std::sqrt(sq_xy / converged));
        }
        conv.push_back(static_cast<double>(converged) / d.sources.size());
        if (g_knobs.verbose > 1) {
          const auto& k = map.counters();
          printf(
              "  doas %ld used %ld gated %ld dup %ld born %ld restarted %ld converged %ld merged "
              "%ld pruned %ld flipped %ld runaway %ld\n",
              (long)k.doas, (long)k.doas_used, (long)k.doas_gated_out, (long)k.doas_duplicate,
              (long)k.sources_born, (long)k.sources_restarted, (long)k.sources_converged,
              (long)k.sources_merged, (long)k.sources_pruned, (long)k.mirrors_flipped,
              (long)k.runaway_solves);
          for (size_t j = 0; j < d.sources.size(); ++j)
            printf("   truth %zu (%.2f %.2f %.2f)\n", j, d.sources[j].x(), d.sources[j].y(),
                   d.sources[j].z());
          for (const auto& source : map.sources())
            printf("   source %ld (%.2f %.2f %.2f) conv %d obs %d tracks %s\n", (long)source.id,
                   source.position_m.x(), source.position_m.y(), source.position_m.z(),
                   source.converged, source.observations,
                   source.track_ids.empty() ? "-" : std::to_string(source.track_ids[0]).c_str());
        }
        if (g_knobs.verbose)
          printf("  run %d: rms %.4f, %d of %zu converged\n", r,
                 converged > 0 ? std::sqrt(sq / converged) : NAN, converged, d.sources.size());
      }
      printf("%s, %s: rms %.4f m (std %.4f; horizontal %.4f), convergence rate %.3f\n",
             traj == 1   ? "trajectory 1 (facing along the path)"
             : traj == 3 ? "trajectory 1 (arcs: 80 deg off the source)"
             : traj == 4 ? "trajectory 1 (facing along the side)"
                         : "trajectory 2",
             true_poses ? "true poses" : "odometry 3 mm / 0.1 deg per step", Mean(rms), Std(rms),
             Mean(rms_xy), Mean(conv));
      fflush(stdout);
    }
  }
}

// Trajectory 1 with the sensor facing the source on the arcs, turned by an offset: §5.5.1 says
// trajectory 1 sees its sources "mostly around 0 degree DOA" (broadside), which facing the
// source gives; exactly facing it leaves a pair's height unobservable, so the offset is swept.
void Table51Offsets(int runs) {
  printf(
      "== Table 5.1, trajectory 1, sensor facing the source on the arcs turned by an offset, %d "
      "runs\n",
      runs);
  for (double offset_deg : {10.0, 20.0, 30.0, 45.0, 60.0, 80.0}) {
    std::vector<double> rms, conv, ok;
    for (int r = 0; r < runs; ++r) {
      LinearSimConfig c;
      c.trajectory = 1;
      c.arc_face_offset_rad = offset_deg * M_PI / 180;
      const LinearRunResult res = RunTable51(c, r);
      rms.push_back(res.rms_m);
      conv.push_back(res.convergence_rate);
      ok.push_back(res.correct_convergence_rate);
    }
    printf("offset %4.0f deg: rms %.4f m (std %.4f), convergence rate %.3f (within 1 m: %.3f)\n",
           offset_deg, Mean(rms), Std(rms), Mean(conv), Mean(ok));
    fflush(stdout);
  }
}

void Fig58(int runs) {
  printf("== Fig. 5.8: convergence rate and RMS against number of hypotheses, %d runs\n", runs);
  printf("conv: converged by the linearity index; ok: converged within 1 m of the truth\n");
  printf("N_h | traj1 conv   ok    rms_m | traj2 conv   ok    rms_m\n");
  for (int nh : {1, 2, 4, 6, 8, 10, 12}) {
    printf("%3d |", nh);
    for (int traj : {1, 2}) {
      std::vector<double> rms, conv, ok;
      for (int r = 0; r < runs; ++r) {
        LinearSimConfig c;
        c.trajectory = traj;
        const LinearRunResult res = RunTable51(c, 1000 + r, nh);
        rms.push_back(res.rms_m);
        conv.push_back(res.convergence_rate);
        ok.push_back(res.correct_convergence_rate);
      }
      printf("  %.3f  %.3f  %7.4f |", Mean(conv), Mean(ok), Mean(rms));
    }
    printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-sound-map-experiments", [&] {
    sarmap::common::ArgParser parser("sarmap-sound-map-experiments",
                                     "Prints the simulation tables of Su 2017 §4.4.1 and §5.5.1.");
    std::string which = "all";
    int runs = 20;
    parser.AddFlag(
        "--table", &which,
        "fig4.5 | fig4.11 | table5.1 | table5.1-offsets | table5.1-online | fig5.8 | all");
    parser.AddFlag("--runs", &runs, "Monte Carlo runs per cell (thesis: 20; Fig. 4.11: 10)");
    MultiHypothesisOptions& h = g_knobs.mapper.hypotheses;
    int anchor_ld = h.linearity_from_anchor, chi2_noise = h.chi2_with_noise, oracle = 0,
        verbose = 0;
    parser.AddFlag("--nh", &g_knobs.mapper.num_hypotheses, "number of hypotheses N_h (table5.1)");
    parser.AddFlag("--ld", &h.linearity_threshold,
                   "linearity-index threshold of convergence (5.27)");
    parser.AddFlag("--anchor-ld", &anchor_ld,
                   "1: linearity index from the anchor as printed (5.23); 0: from the sensor");
    parser.AddFlag("--chi2-noise", &chi2_noise,
                   "1: chi-square with S = HPH' + Q; 0: S = HPH' as printed (5.21)");
    parser.AddFlag("--prune-mean", &h.prune_mean_chi2,
                   "prune when the mean chi-square exceeds this (5.22)");
    parser.AddFlag("--prune-z", &h.prune_z,
                   "also prune above the chi2(n)/n quantile at this z (0: off)");
    parser.AddFlag("--relative-prune", &h.relative_prune_chi2,
                   "likelihood-ratio pruning margin (0: off)");
    parser.AddFlag("--cluster", &h.cluster_radius_m, "survivors must agree within this radius (m)");
    parser.AddFlag("--min-obs", &h.min_observations, "updates before a hypothesis may converge");
    parser.AddFlag("--dmin", &h.min_distance_m, "d_min (rho_0 = 1/(3 d_min))");
    int mirror = g_knobs.mapper.mirror_check;
    parser.AddFlag("--mirror", &mirror,
                   "1: keep a source or its mirror image through the poses' plane, the better");
    parser.AddFlag("--window", &g_knobs.mapper.window_keyframes,
                   "keyframes of the online joint optimisation");
    parser.AddFlag("--updown", &g_knobs.updown_m, "height of the up-and-down moves (m)");
    parser.AddFlag("--landmark-density", &g_knobs.landmark_density,
                   "RGB-D landmarks per m^2 of floor (-1: default)");
    parser.AddFlag("--noise-scale", &g_knobs.noise_scale,
                   "multiplies the simulated DOA noise (1: 10-20 deg)");
    parser.AddFlag("--seed0", &g_knobs.seed0, "first seed of the Monte Carlo runs");
    parser.AddFlag("--oracle", &oracle, "1: sources start converged at the truth (diagnostic)");
    int oracle_poses = 0;
    parser.AddFlag("--oracle-poses", &oracle_poses,
                   "1: the mapper uses the true poses (diagnostic)");
    parser.AddFlag("--verbose", &verbose,
                   "1: one line per run; 2 (table5.1-online): also the map's counters and sources");
    std::string doa = "calibration";
    std::string doa_file = std::string(SARMAP_DATA_DIR) + "/audio/ssm/gp_doa_calibration.csv";
    double quantum_deg = 5;
    parser.AddFlag(
        "--doa", &doa,
        "simulated DOA error (table5.1, fig5.8): calibration (a GP of the real array's error "
        "against the true angle, as §5.5.1) | gaussian (unbiased 10-20 deg noise)");
    parser.AddFlag("--doa-file", &doa_file,
                   "calibration pairs raw_deg,true_deg (--doa calibration)");
    parser.AddFlag("--quantum-deg", &quantum_deg,
                   "raw DOAs rounded to this grid (--doa calibration; 0: off)");
    std::string model = "forward";
    parser.AddFlag(
        "--sensor-model", &model,
        "the mapper's DOA model. With --doa calibration: forward (residuals in the raw angle "
        "through the forward GP), bayes (raw angles corrected by the forward GP inverted with "
        "Bayes' rule) or gp (raw angles corrected by a GP of the truth over the raw angle, eqs. "
        "5.5-5.6). With --doa gaussian: constant (1 deg, a diagnostic) or anything else for the "
        "GP of a simulated calibration");
    std::string variants = "1,3,4,2";
    parser.AddFlag(
        "--variants", &variants,
        "table5.1 rows: 1 (trajectory 1 facing along the path), 3 (arcs 80 deg off the source), "
        "4 (facing along the side), 2 (trajectory 2)");
    if (!parser.Parse(argc, argv)) return 0;
    g_knobs.variants.clear();
    for (char ch : variants)
      if (ch >= '1' && ch <= '4') g_knobs.variants.push_back(ch - '0');
    if (doa == "calibration") {
      std::vector<double> raw, truth;
      LoadDoaCalibrationCsv(doa_file, &raw, &truth);
      g_knobs.doa_quantum_rad = quantum_deg * M_PI / 180;
      const CalibratedDoa cal = FitCalibratedDoa(raw, truth, g_knobs.doa_quantum_rad);
      g_knobs.doa_generator = cal.generator;
      g_knobs.online_sensor_model = cal.sensor_model;
      if (model == "forward") {
        g_knobs.mapper.sensor_model = cal.sensor_model;
        g_knobs.mapper.forward_model = cal.generator;
        g_knobs.mapper.doa_quantum_rad = g_knobs.doa_quantum_rad;
      } else if (model == "bayes") {
        g_knobs.mapper.sensor_model = cal.sensor_model;
      } else if (model == "gp") {
        g_knobs.mapper.sensor_model = cal.thesis_model;
      } else {
        throw std::invalid_argument("--sensor-model must be forward, bayes or gp, not " + model);
      }
    } else if (doa == "gaussian" && model == "constant") {
      g_knobs.mapper.sensor_model = std::make_shared<ConstantDoaModel>(1 * M_PI / 180);
    } else if (doa != "gaussian") {
      throw std::invalid_argument("--doa must be calibration or gaussian, not " + doa);
    }
    g_knobs.mapper.mirror_check = mirror;
    h.linearity_from_anchor = anchor_ld;
    h.chi2_with_noise = chi2_noise;
    g_knobs.mapper.oracle_init = oracle;
    g_knobs.mapper.oracle_poses = oracle_poses;
    g_knobs.verbose = verbose;
    if (which == "fig4.5" || which == "all") Fig45(runs);
    if (which == "fig4.11" || which == "all") Fig411(which == "all" ? std::min(runs, 10) : runs);
    if (which == "table5.1" || which == "all") Table51(runs);
    if (which == "table5.1-offsets") Table51Offsets(runs);
    if (which == "table5.1-online") Table51Online(runs);
    if (which == "fig5.8" || which == "all") Fig58(runs);
    return 0;
  });
}
