// sarmap-log import-rosbag BAG -o LOG: a ROS 1 bag as an LCM log of sarmap messages
// (log-tools/rosbag_convert.h says which types go where).
#include <cstdio>

#include "common/args.h"
#include "common/robot_config.h"
#include "log-tools/rosbag_convert.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log import-rosbag", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log import-rosbag",
        "Converts a ROS 1 bag into an LCM log of sarmap messages: sensor_msgs/LaserScan -> SCAN,\n"
        "nav_msgs/Odometry and /tf odom->base_link -> ODOM, sensor_msgs/Image depth (16UC1 mm,\n"
        "32FC1 m) -> DEPTH, colour (rgb8, bgr8, mono8; CompressedImage JPEG, PNG) -> RGB, with\n"
        "the CameraInfo of the camera's namespace, audio_common_msgs/AudioData(Stamped) ->\n"
        "AUDIO, geometry_msgs/PoseStamped -> POSE, nav_msgs/OccupancyGrid -> MAP,\n"
        "visualization_msgs/MarkerArray (as export-rosbag writes it) -> PEOPLE_MAP. Topics and\n"
        "frame names in config/rosbag.yaml. /tf_static goes to an extrinsics file in\n"
        "config/robot.yaml's form (LOG.robot.yaml).");
    std::string bag, output, config = "config/rosbag.yaml", extrinsics;
    std::vector<std::string> overrides;
    bool list = false;
    parser.AddPositional("BAG", &bag, "ROS 1 bag (.bag)");
    parser.AddFlag("-o", &output, "LCM log to write (default: BAG without .bag + .lcmlog)");
    parser.AddFlag("--config", &config, "options (topics, frames, audio format)");
    parser.AddRepeated("--set", &overrides, "override an option, e.g. --set topics=[/scan=SCAN]");
    parser.AddFlag("--extrinsics", &extrinsics,
                   "where /tf_static goes (default: LOG without extension + .robot.yaml)");
    parser.AddSwitch("--list", &list, "only list the bag's topics, types and counts");
    if (!parser.Parse(argc, argv)) return 0;
    if (list) {
      fputs(sarmap::logtools::FormatTopics(sarmap::logtools::ListBag(bag)).c_str(), stdout);
      return 0;
    }
    const auto options = sarmap::common::LoadOptions<sarmap::logtools::RosbagOptions>(
        sarmap::common::ResolveConfigPath(config), overrides);
    const std::string stem = [](const std::string& p) {
      const size_t dot = p.rfind('.'), slash = p.rfind('/');
      return dot == std::string::npos || (slash != std::string::npos && dot < slash)
                 ? p
                 : p.substr(0, dot);
    }(bag);
    if (output.empty()) output = stem + ".lcmlog";
    if (extrinsics.empty()) {
      const size_t dot = output.rfind('.'), slash = output.rfind('/');
      extrinsics = (dot == std::string::npos || (slash != std::string::npos && dot < slash)
                        ? output
                        : output.substr(0, dot)) +
                   ".robot.yaml";
    }
    const auto result = sarmap::logtools::ImportRosbag(
        bag, output, options, extrinsics,
        [](double f) { fprintf(stderr, "\rimport-rosbag: %5.1f %%", 100 * f); });
    fprintf(stderr, "\n");
    printf("%s -> %s\n%s", bag.c_str(), output.c_str(),
           sarmap::logtools::FormatTopics(result.topics).c_str());
    for (const auto& [channel, n] : result.channel_counts)
      printf("%s: %lld messages\n", channel.c_str(), static_cast<long long>(n));
    for (const auto& w : result.warnings) fprintf(stderr, "warning: %s\n", w.c_str());
    if (!result.extrinsics_path.empty())
      printf("extrinsics (/tf_static): %s\n", result.extrinsics_path.c_str());
    return 0;
  });
}
