// Benchmarks of the sound map (Su 2017 §4.4.1 timings):
//   * one CI sound-map EKF step with 20 sources: back-propagation of [current, 20 anchors]
//     from the localisation map + one bearing update per source heard (thesis: 14.2 ms per
//     step at 185 m; goal < 1 ms);
//   * joint optimisation (Ceres, SPARSE_NORMAL_CHOLESKY) of the 185 m trajectory with
//     landmarks and sources (thesis: 99.4 s; goal < 1 s);
//   * one solve of the map of where the bearings cross (BearingEvidence) with N rays from a
//     robot driving a 20 x 10 m loop among 8 sources (the node solves every 5 s).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <random>

#include "sound_map/bearing_evidence.h"
#include "sound_map/experiments.h"
#include "sound_map/idp_ekf.h"
#include "sound_map/joint_optimizer.h"
#include "handheld_sound_map/linear_array_map.h"
#include "sound_map/simulation.h"

namespace sm = sarmap::sound_map;

namespace {

// A sound map holding `n` sources on `n` anchors, and a localisation-map state to
// back-propagate (joint covariance of current + anchors from an odometry chain).
struct CiFixture {
  sm::IdpEkf sound;
  sm::Pose2 current;
  std::vector<std::pair<int64_t, sm::Pose2>> anchors;
  Eigen::MatrixXd cov;
  std::vector<Eigen::VectorXd> z;
  Eigen::MatrixXd r;
  CiFixture(int n, bool three_d) : sound(Options(three_d)) {
    std::mt19937 rng(1);
    std::normal_distribution<double> n01(0, 1);
    sm::IdpEkf loc(Options(false));
    loc.Reset(sm::Pose2(), Eigen::Matrix3d::Zero());
    sound.Reset(sm::Pose2(), Eigen::Matrix3d::Zero());
    const int m = three_d ? 2 : 1;
    r = Eigen::MatrixXd::Identity(m, m) * std::pow(10 * M_PI / 180, 2);
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < 5; ++k)
        loc.Predict(sm::Pose2(0.2, 0, 0.05), Eigen::Vector3d(4e-4, 4e-4, 7e-3).asDiagonal());
      loc.AddAnchor(i);
      sarmap::sound_map::Pose2 c;
      std::vector<std::pair<int64_t, sm::Pose2>> a;
      Eigen::MatrixXd p;
      loc.SharedState(sound.anchor_ids(), &c, &a, &p);
      sound.BackPropagate(c, a, p);
      Eigen::VectorXd zi = Eigen::VectorXd::Constant(m, 0.3 * n01(rng));
      sound.AddSource(i, i, zi, r);
      z.push_back(zi);
    }
    std::vector<int64_t> ids;
    for (int i = 0; i < n; ++i) ids.push_back(i);
    loc.Predict(sm::Pose2(0.2, 0, 0.0), Eigen::Vector3d(4e-4, 4e-4, 7e-3).asDiagonal());
    loc.SharedState(ids, &current, &anchors, &cov);
  }
  static sm::IdpEkf::Options Options(bool three_d) {
    sm::IdpEkf::Options o;
    o.three_d = three_d;
    return o;
  }
};

void BM_CiSoundMapStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool three_d = state.range(1) != 0;
  const int heard = static_cast<int>(state.range(2));
  CiFixture f(n, three_d);
  for (auto _ : state) {
    sm::IdpEkf sound = f.sound;  // same starting state every iteration
    sound.BackPropagate(f.current, f.anchors, f.cov);
    for (int i = 0; i < heard; ++i) sound.UpdateSource(i, f.z[i], f.r);
    benchmark::DoNotOptimize(sound.mean().data());
  }
  state.SetLabel(std::string(three_d ? "3D" : "2D") + ", " + std::to_string(n) +
                 " sources, state dim " + std::to_string(f.sound.dim()) + ", " +
                 std::to_string(heard) + " heard");
}
BENCHMARK(BM_CiSoundMapStep)
    ->Args({20, 0, 1})
    ->Args({20, 0, 20})
    ->Args({20, 1, 20})
    ->Unit(benchmark::kMicrosecond);

// The copy of the fixture state is part of BM_CiSoundMapStep's time: measure it alone.
void BM_CopyOnly(benchmark::State& state) {
  CiFixture f(20, state.range(0) != 0);
  for (auto _ : state) {
    sm::IdpEkf sound = f.sound;
    benchmark::DoNotOptimize(sound.mean().data());
  }
}
BENCHMARK(BM_CopyOnly)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

sm::Sim2dData Sim185() { return sm::Simulate2d(sm::Fig411Config(45, 0)); }

void BM_JointOptimisation185m(benchmark::State& state) {
  static const sm::Sim2dData d = Sim185();
  sm::JointProblem2d init = sm::JointProblemFromSimulation(d, true);
  init.use_sound_edges = false;
  sm::SolveJoint(&init);  // poses from odometry + landmarks: the starting point
  init.use_sound_edges = true;
  sm::TriangulateSources(&init);
  double solve_s = 0;
  int iterations = 0;
  for (auto _ : state) {
    sm::JointProblem2d p = init;
    const sm::JointReport r = sm::SolveJoint(&p);
    solve_s = r.solve_seconds;
    iterations = r.iterations;
  }
  state.SetLabel(
      std::to_string(d.length_m()) + " m, " + std::to_string(init.poses.size()) + " poses, " +
      std::to_string(init.landmarks.size()) + " landmarks, " + std::to_string(init.sources.size()) +
      " sources, " +
      std::to_string(init.odometry.size() + init.landmark_edges.size() + init.sound_edges.size()) +
      " edges; " + std::to_string(iterations) + " LM iterations, Ceres " + std::to_string(solve_s) +
      " s");
}
BENCHMARK(BM_JointOptimisation185m)->Unit(benchmark::kMillisecond)->Iterations(3);

// The whole offline pipeline as the experiment runs it: initial guess + two solves.
void BM_JointPipeline185m(benchmark::State& state) {
  static const sm::Sim2dData d = Sim185();
  for (auto _ : state) {
    const sm::RunResult r = sm::RunMethod(d, sm::Method::kJoint);
    benchmark::DoNotOptimize(r.score.rms_m);
  }
}
BENCHMARK(BM_JointPipeline185m)->Unit(benchmark::kMillisecond)->Iterations(2);

// One whole CI step at 185 m in the simulation (localisation EKF excluded): mean per step.
void BM_CiSubmaps185mRun(benchmark::State& state) {
  static const sm::Sim2dData d = Sim185();
  sm::RunResult r;
  for (auto _ : state) r = sm::RunMethod(d, sm::Method::kCiSubmaps);
  state.SetLabel("sound-map step mean " + std::to_string(r.sound_step_ms_mean) + " ms, max " +
                 std::to_string(r.sound_step_ms_max) + " ms; RMS " + std::to_string(r.score.rms_m) +
                 " m");
}
BENCHMARK(BM_CiSubmaps185mRun)->Unit(benchmark::kMillisecond)->Iterations(1);

// The hand-held rig's online linear-array map (LinearArraySoundMap) on §5.5.1's trajectory 1:
// odometry-only poses, 8 sources, 3 deg DOAs, one block per 0.2 m step (the map works per DOA
// block, 5-30 per second in use): the time of one block, mean and worst (a windowed or full
// optimisation falls on some blocks).
void BM_LinearArrayMapRun(benchmark::State& state) {
  sm::LinearSimConfig c;
  c.trajectory = 1;
  c.fixed_heading = true;
  c.odo_sigma_m = 0.003;
  c.odo_sigma_rad = 0.1 * M_PI / 180;
  c.landmark_density_per_m2 = 0;
  c.seed = 13;
  static const sm::LinearSimData d = sm::SimulateLinear(c);
  std::vector<double> block_ms;
  for (auto _ : state) {
    block_ms.clear();
    sm::LinearArraySoundMap map{sm::LinearArrayMapOptions()};
    Eigen::Isometry3d odom = d.truth[0];
    for (size_t k = 0; k < d.truth.size(); ++k) {
      if (k > 0) odom = odom * d.odometry[k];
      const int64_t t = static_cast<int64_t>(k) * 400000;
      map.OnPose(t, odom);
      std::vector<sm::LinearArraySoundMap::Doa> doas;
      for (const auto& s : d.sound_obs[k]) {
        sm::LinearArraySoundMap::Doa doa;
        doa.track_id = s.source;
        doa.beta_rad = sm::LinearArrayBeta(d.truth[k], d.sources[s.source]);
        doa.sigma_rad = 3 * M_PI / 180;
        doas.push_back(doa);
      }
      const auto t0 = std::chrono::steady_clock::now();
      map.OnDoa(t, doas);
      block_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    map.Finish();
    benchmark::DoNotOptimize(map.num_keyframes());
  }
  double mean = 0;
  for (double v : block_ms) mean += v;
  mean /= std::max<size_t>(1, block_ms.size());
  state.SetLabel(std::to_string(block_ms.size()) + " blocks: mean " + std::to_string(mean) +
                 " ms, max " + std::to_string(*std::max_element(block_ms.begin(), block_ms.end())) +
                 " ms per block");
}
BENCHMARK(BM_LinearArrayMapRun)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

// BearingEvidence::Solve with N rays, each ray's cells cached from the first solve (as in the
// node, where only the rays since the last solve, or those a loop closure moved, are new).
void BM_BearingEvidenceSolve(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0, 3 * M_PI / 180);
  std::vector<Eigen::Vector2d> sources;
  for (int k = 0; k < 8; ++k) sources.emplace_back(2.5 * k - 1.0, k % 2 ? 8.0 : 2.0);
  sm::BearingEvidence evidence(sm::BearingEvidenceOptions{}, sm::ArrayMount{});
  for (int i = 0; i < n; ++i) {
    const double s = std::fmod(0.05 * i, 60.0);  // along the 60 m loop
    sm::Pose2 pose = s < 20   ? sm::Pose2(s, 0, 0)
                     : s < 30 ? sm::Pose2(20, s - 20, M_PI / 2)
                     : s < 50 ? sm::Pose2(50 - s, 10, M_PI)
                              : sm::Pose2(0, 60 - s, -M_PI / 2);
    // One of the sources within 7 m (a DOA every 0.25 s, heard sources in turn).
    std::vector<const Eigen::Vector2d*> near;
    for (const auto& q : sources)
      if (std::hypot(q.x() - pose.x, q.y() - pose.y) < 7.0) near.push_back(&q);
    if (near.empty()) continue;
    const Eigen::Vector2d& src = *near[static_cast<size_t>(i) % near.size()];
    sm::BearingEvidence::Ray r;
    r.utime = i * 250000;
    r.node_from_base = pose;
    r.azimuth_rad = std::remainder(
        std::atan2(src.y() - pose.y, src.x() - pose.x) - pose.yaw + noise(rng), 2 * M_PI);
    r.sigma_rad = 3 * M_PI / 180;
    r.sound_class = 1;
    evidence.Add(r);
  }
  size_t found = evidence.Solve({}, nullptr, nullptr).size();
  for (auto _ : state) found = evidence.Solve({}, nullptr, nullptr).size();
  state.counters["sources"] = static_cast<double>(found);
}
BENCHMARK(BM_BearingEvidenceSolve)
    ->Arg(3000)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
