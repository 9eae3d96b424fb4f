// sarmap-site: writes a generated incident site as a world file and describes it.
//   sarmap-site --seed 7 -o /tmp/site7.yaml
//   sarmap-site --list 20
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/args.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "sim/floor_plan.h"
#include "sim/site_generator.h"

namespace {

std::string Describe(const sarmap::sim::Site& site, double robot_radius_m) {
  using namespace sarmap::sim;
  return SiteSummary(site, FloorArea(ReachableFloor(site.world, robot_radius_m)));
}

// A top view for checking a layout by eye: reachable floor white, obstacle footprints dark,
// floor the robot cannot cover grey; people red (hidden: magenta, lying: with a line to the
// head), sound sources blue, the robot's start green with its heading. North is up, 2 px per
// 5 cm cell.
void WritePng(const sarmap::sim::Site& site, double robot_radius_m, const std::string& path) {
  using namespace sarmap::sim;
  const World& world = site.world;
  const GridMap g = ReachableFloor(world, robot_radius_m, 0.05);
  const int scale = 2;
  cv::Mat image(g.height * scale, g.width * scale, CV_8UC3);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int v = g.cells[y * g.width + x];
      const cv::Vec3b c = v == 0     ? cv::Vec3b(255, 255, 255)
                          : v == 100 ? cv::Vec3b(60, 60, 60)
                                     : cv::Vec3b(170, 170, 170);
      const cv::Rect cell(x * scale, (g.height - 1 - y) * scale, scale, scale);
      image(cell).setTo(cv::Scalar(c[0], c[1], c[2]));
    }
  }
  const auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(
        static_cast<int>((p.x() - g.origin_x_m) / g.resolution_m * scale),
        static_cast<int>((g.height - (p.y() - g.origin_y_m) / g.resolution_m) * scale));
  };
  for (const SoundSource& s : world.sources)
    cv::circle(image, px(s.position.head<2>()), 5, cv::Scalar(255, 0, 0), -1);
  for (const Person& p : world.people) {
    const bool hidden = std::find(site.hidden_people.begin(), site.hidden_people.end(), p.id) !=
                        site.hidden_people.end();
    const cv::Scalar colour = hidden ? cv::Scalar(255, 0, 255) : cv::Scalar(0, 0, 230);
    cv::circle(image, px(p.position), 8, colour, -1);
    if (p.posture == Posture::kLying) {
      const Eigen::Vector2d head =
          p.position + 0.75 * Eigen::Vector2d(std::cos(p.yaw_rad), std::sin(p.yaw_rad));
      cv::line(image, px(p.position), px(head), colour, 4);
    }
  }
  const Eigen::Vector2d start = world.robot.pose.head<2>();
  cv::circle(image, px(start), static_cast<int>(robot_radius_m / g.resolution_m * scale),
             cv::Scalar(0, 170, 0), 2);
  cv::line(image, px(start),
           px(start + 0.5 * Eigen::Vector2d(std::cos(world.robot.pose.z()),
                                            std::sin(world.robot.pose.z()))),
           cv::Scalar(0, 170, 0), 2);
  if (!cv::imwrite(path, image)) throw sarmap::common::OptionsError(path + ": cannot write");
}

int Run(int argc, char** argv) {
  using namespace sarmap;
  common::ArgParser args(
      "sarmap-site",
      "Generates an incident site for sarmap-sim: a building of rooms joined by a "
      "corridor and doors, with furniture, debris, people (some hidden behind "
      "furniture, only heard), voices, an alarm and machine noise, lit or dark. "
      "The same seed and options give the same world file on every machine; "
      "every room is reachable by the robot from its start.");
  common::NodeArgs node_args;
  int64_t seed = -1;
  std::string out_path;
  int list = 0;
  std::string png_path;
  args.AddNodeOptions(&node_args, "config/site.yaml");
  args.AddFlag("--seed", &seed, "site seed (overrides the seed option)");
  args.AddFlag("-o", &out_path, "write the world file here (default: print it on stdout)");
  args.AddFlag("--list", &list, "print a one-line summary for seeds 1..N instead");
  args.AddFlag("--png", &png_path,
               "also draw the site from above into this PNG (reachable floor white)");
  args.SetEpilog(
      "Prints the world YAML (or writes it with -o and prints a summary: floor area, rooms,\n"
      "reachable floor, people with posture and whether hidden, sound sources, lighting).\n"
      "Options: config/site.yaml, any of them with --set key=value (--print-config lists them).\n"
      "Examples:\n"
      "  sarmap-site --seed 7 -o /tmp/site7.yaml\n"
      "  sarmap-sim --set world=/tmp/site7.yaml --set drive=cmd_vel\n"
      "  sarmap-site --list 20 --set floor_area_m2=300 --set lighting=dark\n");
  if (!args.Parse(argc, argv)) return 0;
  std::vector<std::string> overrides = node_args.overrides;
  if (seed >= 0) overrides.push_back("seed=" + std::to_string(seed));
  const std::string config = common::ResolveConfigPath(node_args.config_path);
  const bool have_config = !config.empty() && std::ifstream(config).good();
  auto options = common::LoadOptions<sim::SiteOptions>(have_config ? config : "", overrides);
  if (node_args.print_config) {
    std::cout << common::OptionsToYaml(options, true);
    return 0;
  }
  if (list > 0) {
    for (int s = 1; s <= list; ++s) {
      options.seed = s;
      std::printf("%s\n",
                  Describe(sim::GenerateSiteLayout(options), options.robot_radius_m).c_str());
    }
    return 0;
  }
  const sim::Site site = sim::GenerateSiteLayout(options);
  const std::string summary = Describe(site, options.robot_radius_m);
  const std::string yaml =
      sim::WorldToYaml(site.world, sim::SiteHeader(options) + "# " + summary + "\n");
  if (!png_path.empty()) WritePng(site, options.robot_radius_m, png_path);
  if (out_path.empty()) {
    std::cout << yaml;
    return 0;
  }
  std::ofstream out(out_path);
  if (!out || !(out << yaml)) throw common::OptionsError(out_path + ": cannot write");
  std::printf("%s\nwrote %s\n", summary.c_str(), out_path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-site", [&] { return Run(argc, argv); });
}
