#pragma once
// The simulator core (no LCM): advances simulated time and emits ODOM, DEPTH, RGB, AUDIO
// (or AUDIO_<DEVICE>), SIM_TRUTH and SIM_FLOOR messages through a SimSink, in time order. The node
// (sim_node.cc) publishes them on LCM; tests and the benchmark collect them in process.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/robot_config.h"
#include "common/transform.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/image_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sim/sim_options.h"
#include "sim/world.h"

namespace sarmap {
namespace sim {

class SimSink {
 public:
  virtual ~SimSink() = default;
  virtual void Publish(const std::string& channel, const sarmap::odometry_t& msg) = 0;
  virtual void Publish(const std::string& channel, const sarmap::image_t& msg) = 0;
  virtual void Publish(const std::string& channel, const sarmap::audio_frame_t& msg) = 0;
  virtual void Publish(const std::string& channel, const sarmap::sim_truth_t& msg) = 0;
  virtual void Publish(const std::string& channel, const sarmap::occupancy_grid_t& msg) = 0;
};

// Everything the simulator needs, with paths resolved.
struct SimSetup {
  SimOptions options;
  World world;
  common::RobotOptions robot;
  common::MicArrayOptions array;
  std::string data_dir;  // absolute or relative to the working directory
};

// Loads the world, robot and array files named by `options` (relative paths against
// `repo_root`, "" = working directory). Throws WorldError / OptionsError.
SimSetup LoadSetup(const SimOptions& options, const std::string& repo_root);
// The repository root for a config or world path: the parent of the nearest "config"
// directory above it, else "".
std::string FindRepoRoot(const std::string& path);

// CPU seconds spent per part (thread CPU time), for the benchmark.
struct SimTiming {
  double physics_s = 0, render_s = 0, encode_s = 0, audio_s = 0, total_s = 0;
};

class Simulator {
 public:
  explicit Simulator(const SimSetup& setup);
  ~Simulator();

  // Latest velocity command (CMD_VEL), at simulated time `utime`.
  void SetVelocityCommand(double linear_mps, double angular_radps);
  // Advances to simulated time t_s (seconds since start), emitting everything due.
  void AdvanceTo(double t_s, SimSink* sink);
  double time_s() const { return t_; }
  int64_t utime() const;
  int64_t start_utime() const { return start_utime_; }

  const std::vector<std::string>& warnings() const { return warnings_; }
  const SimTiming& timing() const { return timing_; }
  const World& world() const { return setup_.world; }
  common::Rigid2d map_from_base() const;
  // The base's contacts with obstacles so far, and the last one.
  int collisions() const;
  const struct Contact& last_contact() const;
  // The camera's optical frame in the map at the current pose.
  common::Rigid3d map_from_camera() const;
  // Renders the current view without publishing (tests): raw RGB and depth in mm, plus each
  // person's visible body box.
  struct View {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
    std::vector<uint16_t> depth_mm;
    std::vector<int> person_pixels;
    std::vector<std::array<int, 4>> person_box;
  };
  View RenderView();
  // Teleports the robot (tests).
  void SetRobotPose(const common::Rigid2d& map_from_base);
  int appearance_count() const;
  class AudioSim* audio();
  const class Renderer* renderer() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  SimSetup setup_;
  double t_ = 0;
  int64_t start_utime_ = 0;
  std::vector<std::string> warnings_;
  SimTiming timing_;
};

}  // namespace sim
}  // namespace sarmap
