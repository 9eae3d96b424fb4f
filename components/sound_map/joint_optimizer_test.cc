// The joint optimisation built from a recorded trajectory and DOAs (JointProblemFromLog).
#include "sound_map/joint_optimizer.h"

#include <gtest/gtest.h>

#include <random>

namespace sarmap {
namespace sound_map {
namespace {

TEST(JointProblemFromLog, PlacesSourcesFromATrajectoryAndLeavesStrayBearingsOut) {
  // A robot drives 6 m along x and back along y = 1; two sources beside the path; the array
  // 0.1 m ahead of the base, turned 90 deg. DOAs with 2 deg of noise, plus one stray bearing
  // per block that fits neither source.
  ArrayMount mount;
  mount.x_m = 0.1;
  mount.yaw_rad = M_PI / 2;
  const std::vector<Eigen::Vector3d> truth = {{2.0, 3.0, 0}, {4.5, -2.0, 0}};
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01(0, 1);
  std::vector<Pose2> poses;
  std::vector<std::vector<LogBearing>> bearings;
  for (int k = 0; k <= 60; ++k) {
    const Pose2 p = k <= 30 ? Pose2(0.2 * k, 0, 0) : Pose2(6.0 - 0.2 * (k - 30), 1.0, M_PI);
    poses.push_back(p);
    std::vector<LogBearing> b;
    const double pose[3] = {p.x, p.y, p.yaw};
    std::vector<double> true_azimuths;
    for (const auto& s : truth) {
      double h[2];
      PointObservation(pose, s.data(), false, mount, h);
      true_azimuths.push_back(h[0]);
      LogBearing lb;
      lb.azimuth_rad = h[0] + 2.0 * M_PI / 180 * n01(rng);
      lb.sigma_rad = 2.0 * M_PI / 180;
      b.push_back(lb);
    }
    LogBearing stray;  // at least 40 deg from both sources' bearings
    stray.sigma_rad = 2.0 * M_PI / 180;
    for (double a = -M_PI; a < M_PI; a += 0.1) {
      bool clear = true;
      for (double t : true_azimuths) clear = clear && std::abs(WrapAngle(a - t)) > 40 * M_PI / 180;
      if (clear) {
        stray.azimuth_rad = a;
        break;
      }
    }
    b.push_back(stray);
    bearings.push_back(b);
  }
  // The CI map's estimates as the guess: 0.4-0.5 m off.
  const std::vector<Eigen::Vector3d> init = {{2.3, 3.4, 0}, {4.1, -1.8, 0}};
  LogJointOptions o;
  // Against the guess alone, many bearings miss the gate ...
  const JointProblem2d first = JointProblemFromLog(poses, bearings, init, mount, false, o);
  EXPECT_EQ(first.poses.size(), 61u);
  EXPECT_EQ(first.odometry.size(), 60u);
  EXPECT_LT(first.sound_edges.size(), 2u * 61u);
  // ... solving and associating again takes them all, and no stray one.
  JointProblem2d problem;
  const JointReport report = SolveJointFromLog(poses, bearings, init, mount, false, o, &problem);
  EXPECT_EQ(problem.sound_edges.size(), 2u * 61u);
  EXPECT_TRUE(report.usable);
  for (int j = 0; j < 2; ++j) {
    const double error = (problem.sources[j] - truth[j]).head<2>().norm();
    printf("source %d: %.3f m from the truth (guess %.3f m)\n", j, error,
           (init[j] - truth[j]).head<2>().norm());
    EXPECT_LT(error, 0.1);
  }
  // The trajectory keeps its shape: the last pose stays within a few centimetres.
  EXPECT_LT(
      std::hypot(problem.poses.back().x - poses.back().x, problem.poses.back().y - poses.back().y),
      0.05);
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
