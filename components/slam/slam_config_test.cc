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

TEST(SlamConfigTest, KinectRobotFileChangesOnlyRotationPriorAndLocalTies) {
  const auto base = common::LoadOptions<SlamNodeOptions>(kConfigDir + "slam.yaml", {});
  const auto robot = common::LoadOptions<SlamNodeOptions>(kConfigDir + "slam_kinect_robot.yaml", {});
  EXPECT_FALSE(base.slam.local.ceres_rotation_prior_from_prediction);
  EXPECT_TRUE(robot.slam.local.ceres_rotation_prior_from_prediction);
  EXPECT_GT(robot.slam.graph.local_slam_translation_weight,
            base.slam.graph.local_slam_translation_weight);

  // Everything else is inherited: the printed options differ in exactly those two lines.
  const auto base_lines = Lines(common::OptionsToYaml(base, false));
  const auto robot_lines = Lines(common::OptionsToYaml(robot, false));
  ASSERT_EQ(base_lines.size(), robot_lines.size());
  std::vector<std::string> differing;
  for (size_t i = 0; i < base_lines.size(); ++i) {
    if (base_lines[i] != robot_lines[i]) differing.push_back(robot_lines[i]);
  }
  ASSERT_EQ(differing.size(), 2u);
  EXPECT_NE(differing[0].find("ceres_rotation_prior_from_prediction"), std::string::npos);
  EXPECT_NE(differing[1].find("local_slam_translation_weight"), std::string::npos);
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
