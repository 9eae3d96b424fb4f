// The shipped SLAM configurations: config/slam.yaml (the laser benchmark logs) and the robot
// files that extend it must load, validate, and differ from their base only where they say so.

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "common/options.h"
#include "slam/slam_node_options.h"

namespace sarmap {
namespace slam {
namespace {

const std::string kConfigDir = std::string(SARMAP_SOURCE_DIR) + "/config/";

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(SlamConfigTest, KinectRobotFileChangesOnlyWhatItStates) {
  const auto base = common::LoadOptions<SlamNodeOptions>(kConfigDir + "slam.yaml", {});
  const auto robot = common::LoadOptions<SlamNodeOptions>(kConfigDir + "slam_kinect_robot.yaml", {});
  EXPECT_FALSE(base.slam.local.ceres_rotation_prior_from_prediction);
  EXPECT_TRUE(robot.slam.local.ceres_rotation_prior_from_prediction);
  EXPECT_GT(robot.slam.graph.local_slam_translation_weight,
            base.slam.graph.local_slam_translation_weight);

  // The laser logs keep the covariance of the weights; the robot states its constraints' noise.
  EXPECT_EQ(base.slam.covariance.intra_sigma_m, 0);
  EXPECT_GT(robot.slam.covariance.intra_sigma_m, 0);
  EXPECT_GT(robot.slam.covariance.local_slam_sigma_deg, 0);

  // Good odometry: the scan matcher's priors stay strong.
  EXPECT_GE(robot.slam.local.ceres_translation_weight, base.slam.local.ceres_translation_weight);
  EXPECT_GE(robot.slam.local.ceres_rotation_weight, base.slam.local.ceres_rotation_weight);

  // The laser benchmark keeps a fixed rotation prior; the robot adapts it to each scan.
  EXPECT_EQ(base.slam.local.ceres_rotation_weight_informative, 0);
  EXPECT_GT(robot.slam.local.ceres_rotation_weight_informative, 0);

  // A narrow depth scan matches only where the submap knows the space; a laser matches all.
  EXPECT_FALSE(base.slam.local.match_known_space_only);
  EXPECT_TRUE(robot.slam.local.match_known_space_only);

  // A live driver repeats odometry while the robot stands; CARMEN logs freeze it while moving.
  EXPECT_FALSE(base.slam.local.unchanged_odometry_means_stopped);
  EXPECT_TRUE(robot.slam.local.unchanged_odometry_means_stopped);
  EXPECT_EQ(base.slam.local.odometry_extrapolation_s, 0);
  EXPECT_GT(robot.slam.local.odometry_extrapolation_s, 0);
  // The robot's loop-closure search stays near its own estimate (a Kinect scan is ambiguous).
  EXPECT_LT(robot.slam.loop.linear_window_m, base.slam.loop.linear_window_m);

  // ... and keeps only closures that agree with its graph and lie inside that window.
  EXPECT_FALSE(base.slam.loop.consistency_gate);
  EXPECT_TRUE(robot.slam.loop.consistency_gate);
  EXPECT_FALSE(base.slam.loop.reject_window_edge);
  EXPECT_TRUE(robot.slam.loop.reject_window_edge);

  // A depth scan's "no return" is free space only up to the sensor's range limit.
  EXPECT_LT(robot.slam.scan.missing_data_ray_length_m, base.slam.scan.missing_data_ray_length_m);

  // Both trim submaps that map nothing new: a long mission's graph grows with the site.
  EXPECT_TRUE(base.slam.trim.enabled);
  EXPECT_TRUE(robot.slam.trim.enabled);

  // Everything else is inherited: the printed options differ only in those lines.
  const auto base_lines = Lines(common::OptionsToYaml(base, false));
  const auto robot_lines = Lines(common::OptionsToYaml(robot, false));
  ASSERT_EQ(base_lines.size(), robot_lines.size());
  std::vector<std::string> differing;
  for (size_t i = 0; i < base_lines.size(); ++i) {
    if (base_lines[i] != robot_lines[i]) differing.push_back(robot_lines[i]);
  }
  const std::vector<std::string> allowed = {"ceres_translation_weight",
                                            "ceres_rotation_weight",
                                            "ceres_rotation_prior_from_prediction",
                                            "ceres_rotation_weight_informative",
                                            "rotation_information_low",
                                            "rotation_information_high",
                                            "local_slam_translation_weight",
                                            "intra_sigma_m",
                                            "intra_sigma_deg",
                                            "loop_sigma_m",
                                            "loop_sigma_deg",
                                            "odometry_sigma_m",
                                            "odometry_sigma_deg",
                                            "local_slam_sigma_m",
                                            "local_slam_sigma_deg",
                                            "unchanged_odometry_means_stopped",
                                            "odometry_extrapolation_s",
                                            "match_known_space_only",
                                            "linear_window_m",
                                            "consistency_gate",
                                            "reject_window_edge",
                                            "missing_data_ray_length_m"};
  EXPECT_GE(differing.size(), 2u);
  for (const auto& line : differing) {
    bool known = false;
    for (const auto& key : allowed) known |= line.find(key + ":") != std::string::npos;
    EXPECT_TRUE(known) << "slam_kinect_robot.yaml changes an unexpected key: " << line;
  }
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
