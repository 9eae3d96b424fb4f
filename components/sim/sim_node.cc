// sarmap-sim: the embedded default world. Publishes ODOM, DEPTH, RGB, AUDIO (or
// AUDIO_<DEVICE>), SIM_TRUTH and SIM_FLOOR in simulated time, follows CMD_VEL.
#include <chrono>
#include <fstream>
#include <map>
#include <cmath>
#include <iostream>
#include <thread>

#include "common/args.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "common/command_auth.h"
#include "sarmap/velocity_command_t.hpp"
#include "sim/robot.h"
#include "sim/simulator.h"

namespace {

using sarmap::common::Node;

// Publishes what the simulator emits on LCM (the publisher fills header.seq per channel).
class LcmSink : public sarmap::sim::SimSink {
 public:
  explicit LcmSink(Node* node) : node_(node) {}
  void Publish(const std::string& ch, const sarmap::odometry_t& m) override { Send(odom_, ch, m); }
  void Publish(const std::string& ch, const sarmap::image_t& m) override { Send(image_, ch, m); }
  void Publish(const std::string& ch, const sarmap::audio_frame_t& m) override { Send(audio_, ch, m); }
  void Publish(const std::string& ch, const sarmap::sim_truth_t& m) override { Send(truth_, ch, m); }
  void Publish(const std::string& ch, const sarmap::occupancy_grid_t& m) override { Send(grid_, ch, m); }

 private:
  template <class T>
  void Send(std::map<std::string, Node::Publisher<T>>& pubs, const std::string& channel, const T& msg) {
    auto it = pubs.find(channel);
    if (it == pubs.end()) it = pubs.emplace(channel, node_->Advertise<T>(channel)).first;
    T copy = msg;
    it->second.Publish(&copy);
  }
  Node* node_;
  std::map<std::string, Node::Publisher<sarmap::odometry_t>> odom_;
  std::map<std::string, Node::Publisher<sarmap::image_t>> image_;
  std::map<std::string, Node::Publisher<sarmap::audio_frame_t>> audio_;
  std::map<std::string, Node::Publisher<sarmap::sim_truth_t>> truth_;
  std::map<std::string, Node::Publisher<sarmap::occupancy_grid_t>> grid_;
};

int Run(int argc, char** argv) {
  using namespace sarmap;
  common::ArgParser args("sarmap-sim",
                         "The embedded default world: a simulated incident site with an RGB-D camera, "
                         "a microphone array and odometry, in simulated time.");
  common::NodeArgs node_args;
  std::string world;
  double speed = -1;
  int64_t seed = -1;
  double duration = -1;
  args.AddNodeOptions(&node_args, "config/sim.yaml");
  args.AddFlag("--world", &world, "world file (overrides the world option)");
  args.AddFlag("--speed", &speed, "simulated seconds per wall second; 0 = as fast as possible");
  args.AddFlag("--seed", &seed, "random seed (same seed, same run)");
  args.AddFlag("--duration", &duration, "stop after this many simulated seconds");
  args.SetEpilog(
      "Channels out: ODOM, DEPTH, RGB, AUDIO (AUDIO_<DEVICE> per microphone for an asynchronous\n"
      "array), SIM_TRUTH, SIM_FLOOR. In: CMD_VEL. Worlds: config/worlds/*.yaml, or generated\n"
      "by sarmap-site.\n"
      "Example: sarmap-sim --world config/worlds/lab_dark.yaml --speed 2 --seed 7\n");
  if (!args.Parse(argc, argv)) return 0;
  common::SetLogLevel(common::ParseLogLevel(node_args.log_level));
  std::vector<std::string> overrides = node_args.overrides;
  if (!world.empty()) overrides.push_back("world=" + world);
  if (speed >= 0) overrides.push_back("speed=" + std::to_string(speed));
  if (seed >= 0) overrides.push_back("seed=" + std::to_string(seed));
  if (duration >= 0) overrides.push_back("duration_s=" + std::to_string(duration));
  // The config file is found like every node's (working directory, $SARMAP_CONFIG_DIR, the
  // source tree's config/).
  const std::string config = common::ResolveConfigPath(node_args.config_path);
  const bool have_config = !config.empty() && std::ifstream(config).good();
  const auto options = common::LoadOptions<sim::SimOptions>(have_config ? config : "", overrides);
  if (node_args.print_config) {
    std::cout << common::OptionsToYaml(options, true);
    return 0;
  }
  // Relative paths in the options are taken from the repository holding the config file
  // (or the working directory).
  std::string root = have_config ? sim::FindRepoRoot(config) : "";
  sim::SimSetup setup;
  try {
    setup = sim::LoadSetup(options, root);
  } catch (const sim::WorldError& e) {
    throw common::OptionsError(e.what());
  }
  Node node("sarmap-sim", node_args);
  sim::Simulator simulator(setup);
  for (const std::string& w : simulator.warnings()) SARMAP_LOG(WARN) << w;
  SARMAP_LOG(INFO) << "world '" << setup.world.name << "' (" << setup.world.source_file << "), array '"
                   << setup.array.name << "' (" << setup.array.num_mics() << " mics), speed "
                   << options.speed << ", seed " << options.seed;
  // With a command key the base obeys only signed, fresh commands (a forged or replayed
  // CMD_VEL on the bus is counted and dropped), as a robot's base driver would.
  common::CommandGate command_gate;
  if (!options.command_key_file.empty()) {
    command_gate = common::CommandGate(common::LoadAuthKeyFile(options.command_key_file));
  } else if (options.drive != "path") {
    SARMAP_LOG(WARN) << "no command_key_file: any CMD_VEL on the bus drives the robot";
  }
  node.Subscribe<sarmap::velocity_command_t>(
      options.channels.cmd_vel, [&](const sarmap::velocity_command_t& cmd, const common::ReceiveInfo& info) {
        std::string why;
        if (!command_gate.Accept(cmd, &why, simulator.utime())) {
          node.Reject(info.channel, "CMD_VEL " + why);
          return;
        }
        if (std::isfinite(cmd.linear_mps) && std::isfinite(cmd.angular_radps)) {
          simulator.SetVelocityCommand(cmd.linear_mps, cmd.angular_radps);
        }
      }, 5);
  LcmSink sink(&node);
  // Its own loop, not Node::Run(): NODE_STATUS from the timer that SpinOnce serves.
  node.AddTimer(1.0, [&node] { node.PublishStatus(); });
  const double step_s = 1.0 / 100;  // advance in 10 ms slices, serving LCM in between
  const auto wall0 = std::chrono::steady_clock::now();
  double last_status = -1;
  int collisions = 0;
  while (!node.stopping()) {
    if (options.duration_s > 0 && simulator.time_s() >= options.duration_s - 1e-9) break;
    simulator.AdvanceTo(simulator.time_s() + step_s, &sink);
    if (simulator.collisions() > collisions) {
      collisions = simulator.collisions();
      const sim::Contact& c = simulator.last_contact();
      SARMAP_LOG(WARN) << "collision " << collisions << " at t=" << c.t_s << " s: the base at ("
                       << c.map_from_base.translation().x() << ", " << c.map_from_base.translation().y()
                       << ") m, heading " << c.map_from_base.yaw_rad() * 180 / M_PI
                       << " deg, touched the " << c.what;
    }
    // Serve LCM (CMD_VEL) every step, also when running behind the requested speed (a few
    // non-blocking rounds: each handles at most one message).
    for (int k = 0; k < 4 && !node.stopping(); ++k) node.SpinOnce(0.0);
    if (options.speed > 0) {
      const auto due = wall0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(simulator.time_s() / options.speed));
      while (!node.stopping()) {
        const double left = std::chrono::duration<double>(due - std::chrono::steady_clock::now()).count();
        if (left <= 0) break;
        if (!node.SpinOnce(left)) break;
      }
    }
    if (simulator.time_s() - last_status >= 1.0) {
      last_status = simulator.time_s();
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      node.SetStatusMessage("sim t=" + std::to_string(simulator.time_s()) + " s, " +
                            std::to_string(wall > 0 ? simulator.time_s() / wall : 0.0) + "x real time");
    }
  }
  SARMAP_LOG(INFO) << "stopped at simulated t=" << simulator.time_s() << " s";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-sim", [&] { return Run(argc, argv); });
}
