// sarmap-sim-snapshot: renders what the simulated camera sees, to preview a world file.
//   sarmap-sim-snapshot --world config/worlds/lab_lit.yaml --time 2.5 --out /tmp/lab
// writes <out>_rgb.png and <out>_depth.png (depth false-coloured, black = no reading).
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/args.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "sim/simulator.h"

namespace {
struct NullSink : sarmap::sim::SimSink {
  void Publish(const std::string&, const sarmap::odometry_t&) override {}
  void Publish(const std::string&, const sarmap::image_t&) override {}
  void Publish(const std::string&, const sarmap::audio_frame_t&) override {}
  void Publish(const std::string&, const sarmap::sim_truth_t&) override {}
  void Publish(const std::string&, const sarmap::occupancy_grid_t&) override {}
};
}  // namespace

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunMain("sarmap-sim-snapshot", [&] {
    common::ArgParser args("sarmap-sim-snapshot",
                           "Render the simulated camera's view of a world to PNG files.");
    common::NodeArgs node_args;
    std::string world, out = "snapshot";
    double time_s = 0;
    args.AddNodeOptions(&node_args, "config/sim.yaml");
    args.AddFlag("--world", &world, "world file");
    args.AddFlag("--time", &time_s, "simulated time of the snapshot (the robot follows its path)");
    args.AddFlag("--out", &out, "output prefix");
    if (!args.Parse(argc, argv)) return 0;
    std::vector<std::string> overrides = node_args.overrides;
    if (!world.empty()) overrides.push_back("world=" + world);
    overrides.push_back("audio.enabled=false");
    const std::string config = common::ResolveConfigPath(node_args.config_path);
    const bool have_config = std::ifstream(config).good();
    const auto options = common::LoadOptions<sim::SimOptions>(have_config ? config : "", overrides);
    sim::SimSetup setup;
    try {
      setup = sim::LoadSetup(options, have_config ? sim::FindRepoRoot(config) : "");
    } catch (const sim::WorldError& e) {
      throw common::OptionsError(e.what());
    }
    sim::Simulator simulator(setup);
    for (const auto& w : simulator.warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
    NullSink sink;
    simulator.AdvanceTo(time_s, &sink);
    const sim::Simulator::View view = simulator.RenderView();
    cv::Mat rgb(view.height, view.width, CV_8UC3, const_cast<uint8_t*>(view.rgb.data())), bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    cv::imwrite(out + "_rgb.png", bgr);
    cv::Mat depth(view.height, view.width, CV_16UC1, const_cast<uint16_t*>(view.depth_mm.data())),
        scaled, coloured;
    depth.convertTo(scaled, CV_8UC1, 255.0 / 5000.0);
    cv::applyColorMap(scaled, coloured, cv::COLORMAP_JET);
    coloured.setTo(cv::Scalar(0, 0, 0), depth == 0);
    cv::imwrite(out + "_depth.png", coloured);
    const auto pose = simulator.map_from_base();
    std::printf("robot at x=%.2f y=%.2f yaw=%.2f; wrote %s_rgb.png, %s_depth.png\n",
                pose.translation().x(), pose.translation().y(), pose.yaw_rad(), out.c_str(),
                out.c_str());
    return 0;
  });
}
