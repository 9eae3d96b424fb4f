// sarmap-log export-rosbag LOG -o BAG: sarmap's results (POSE, MAP, PEOPLE_MAP) as standard ROS
// messages, for RViz, rqt_bag and rosbag play.
#include <cstdio>

#include "common/args.h"
#include "common/robot_config.h"
#include "log-tools/rosbag_convert.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log export-rosbag", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log export-rosbag",
        "Writes a mission's POSE (geometry_msgs/PoseStamped, /sarmap/pose), MAP\n"
        "(nav_msgs/OccupancyGrid, /map) and PEOPLE_MAP (visualization_msgs/MarkerArray, one\n"
        "SPHERE per person in namespace 'people', 1-sigma diameters, /sarmap/people) into a ROS 1\n"
        "bag (LZ4 chunks). Topics and frame names in config/rosbag.yaml.");
    std::string log, output, config = "config/rosbag.yaml";
    std::vector<std::string> overrides;
    parser.AddPositional("LOG", &log, "LCM log of the mission");
    parser.AddFlag("-o", &output, "bag to write (default: LOG without extension + .bag)");
    parser.AddFlag("--config", &config, "options (topics, frames)");
    parser.AddRepeated("--set", &overrides, "override an option, e.g. --set map_topic=/sarmap/map");
    if (!parser.Parse(argc, argv)) return 0;
    const auto options = sarmap::common::LoadOptions<sarmap::logtools::RosbagOptions>(
        sarmap::common::ResolveConfigPath(config), overrides);
    if (output.empty()) {
      const size_t dot = log.rfind('.'), slash = log.rfind('/');
      output = (dot == std::string::npos || (slash != std::string::npos && dot < slash)
                    ? log
                    : log.substr(0, dot)) +
               ".bag";
    }
    const auto result = sarmap::logtools::ExportRosbag(log, output, options, [](double f) {
      fprintf(stderr, "\rexport-rosbag: %5.1f %%", 100 * f);
    });
    fprintf(stderr, "\n");
    printf("%s -> %s\n", log.c_str(), output.c_str());
    if (result.topic_counts.empty()) {
      fprintf(stderr, "export-rosbag: the log has no %s, %s or %s messages\n",
              options.pose_channel.c_str(), options.map_channel.c_str(),
              options.people_channel.c_str());
      return 3;
    }
    for (const auto& [topic, n] : result.topic_counts)
      printf("  %-24s %lld messages\n", topic.c_str(), static_cast<long long>(n));
    return 0;
  });
}
