#pragma once
// A whole autonomous mission in one process, in simulated time: the simulator core renders
// depth and odometry; the depth-to-scan converter, graph SLAM and the explorer run on them as
// sarmap-depth, sarmap-slam and sarmap-explore do over LCM, and the explorer's commands drive
// the simulated base. No LCM, no wall clock: a 10-minute mission runs as fast as the CPU
// allows and the same seed gives the same mission. The benchmark (sarmap-mission-bench) runs
// it over generated sites and compares exploration modes.

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/sim_truth_t.hpp"

namespace sarmap {
namespace mission {

struct MissionRunOptions {
  std::string world;                                     // world YAML
  std::string sim_config = "config/sim.yaml";
  std::string slam_config = "config/slam_kinect_robot.yaml";
  std::string explore_config = "config/explore.yaml";
  std::string depth_config = "config/depth.yaml";
  std::string mode = "";             // overrides explore.mode when not empty
  double duration_s = 600;
  double camera_rate_hz = 15;        // depth frames (and scans) per simulated second
  double map_period_s = 0;           // SLAM renders the map this often; 0: the SLAM file's map_period_s
  int64_t seed = 1;
  std::vector<std::string> sim_overrides;
  std::vector<std::string> explore_overrides;
  std::vector<std::string> slam_overrides;
  std::vector<std::string> depth_overrides;
  std::string explorer_map_pgm;      // when set: the explorer's final picture is written here
  std::string slam_map_pgm;          // when set: SLAM's final map is written here
};

// One sample of the mission, every `sample_period_s` of simulated time.
struct MissionSample {
  double t_s = 0;
  Eigen::Vector3d truth_pose = Eigen::Vector3d::Zero();  // world x, y, yaw
  Eigen::Vector3d slam_pose = Eigen::Vector3d::Zero();   // map x, y, yaw
  std::string state;
  int collisions = 0;
  double distance_m = 0;
};

struct MissionResult {
  double simulated_s = 0;
  double cpu_s = 0;                  // whole process
  double explore_cpu_s = 0;          // the explorer alone
  double distance_m = 0;
  int collisions = 0;
  std::vector<std::string> contacts;  // each collision: when, where (world frame) and against what
  int recoveries = 0;
  bool came_home = false;
  double home_after_s = -1;
  std::string final_state;
  std::vector<MissionSample> samples;
};

// Called for every message the simulator emits (truth, floor), the SLAM map when it is
// rendered, and the explorer's status, so that metrics can be computed in the same pass.
// Times are simulated seconds since the start.
struct MissionObserver {
  virtual ~MissionObserver() = default;
  virtual void OnTruth(double /*t_s*/, const sarmap::sim_truth_t& /*truth*/) {}
  virtual void OnFloor(double /*t_s*/, const sarmap::occupancy_grid_t& /*floor*/) {}
  virtual void OnMap(double /*t_s*/, const sarmap::occupancy_grid_t& /*map*/) {}
  virtual void OnExploreStatus(double /*t_s*/, const sarmap::explore_status_t& /*status*/) {}
};

// Runs one mission. Throws on bad configuration (OptionsError, WorldError).
MissionResult RunMission(const MissionRunOptions& options, MissionObserver* observer = nullptr,
                         const std::function<void(double t_s)>& progress = nullptr);

}  // namespace mission
}  // namespace sarmap
