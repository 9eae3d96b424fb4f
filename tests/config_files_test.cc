// Every file in config/ loads through the options struct of the program that reads it, and
// validates: a key renamed in code, or a value out of range in a file, fails here rather than
// when a user starts the program. A new config file must be added to the table.
#include <dirent.h>
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "audio_capture/audio_source.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "depth/depth_node_options.h"
#include "explore/explore_node_options.h"
#include "log-tools/record_profile.h"
#include "log-tools/rosbag_convert.h"
#include "mic_calibrate/mic_calibrate_options.h"
#include "people_map/people_map_intake.h"
#include "procman/procman_options.h"
#include "rgbd_odometry/rgbd_odometry_node_options.h"
#include "sim/sim_options.h"
#include "sim/site_generator.h"
#include "sim/world.h"
#include "slam/slam_node_options.h"
#include "sound_localisation/doa_stream.h"
#include "sound_map/handheld_sound_map_messages.h"
#include "sound_map/sound_map_messages.h"
#include "speech/speech_messages.h"
#include "teleop/teleop.h"
#include "viewer/viewer_options.h"
#include "vision_people/vision_people_options.h"

namespace sarmap {
namespace {

const std::string kConfig = std::string(SARMAP_SOURCE_DIR) + "/config/";

// `overrides`: what the program's command line must add (e.g. the file to read).
template <class Options>
std::function<void(const std::string&)> Loads(std::vector<std::string> overrides = {}) {
  return [overrides](const std::string& path) { common::LoadOptions<Options>(path, overrides); };
}

std::set<std::string> YamlFiles(const std::string& dir) {
  std::set<std::string> out;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 5 && name.compare(name.size() - 5, 5, ".yaml") == 0) out.insert(name);
    }
    closedir(d);
  }
  return out;
}

TEST(ConfigFiles, EveryConfigFileLoadsThroughItsOptions) {
  const std::map<std::string, std::function<void(const std::string&)>> loaders = {
      {"audio_capture.yaml", Loads<audio::CaptureOptions>({"file=recording.wav"})},  // --file
      {"depth.yaml", Loads<depth::DepthNodeOptions>()},
      {"explore.yaml", Loads<explore::ExploreNodeOptions>()},
      {"handheld_sound_map.yaml", Loads<sound_map::HandheldSoundMapOptions>()},
      {"mic_calibrate.yaml", Loads<mic_calibrate::MicCalibrateOptions>()},
      {"people_map.yaml", Loads<people_map::PeopleMapNodeOptions>()},
      {"procman.yaml", Loads<procman::ProcmanOptions>()},
      {"record_long.yaml", Loads<logtools::RecordProfileOptions>()},
      {"rgbd_odometry.yaml", Loads<rgbd_odometry::RgbdOdometryNodeOptions>()},
      {"robot.yaml", Loads<common::RobotOptions>()},
      {"rosbag.yaml", Loads<logtools::RosbagOptions>()},
      {"sim.yaml", Loads<sim::SimOptions>()},
      {"site.yaml", Loads<sim::SiteOptions>()},
      {"slam.yaml", Loads<slam::SlamNodeOptions>()},
      {"slam_kinect_robot.yaml", Loads<slam::SlamNodeOptions>()},
      {"sound_localisation.yaml", Loads<sound::SoundLocalisationOptions>()},
      {"sound_map.yaml", Loads<sound_map::SoundMapNodeOptions>()},
      {"speech.yaml", Loads<speech::SpeechNodeOptions>()},
      {"teleop.yaml", Loads<teleop::TeleopOptions>()},
      {"viewer.yaml", Loads<viewer::ViewerNodeOptions>()},
      {"vision_people.yaml", Loads<vision_people::VisionPeopleOptions>()},
  };
  const std::set<std::string> files = YamlFiles(kConfig);
  ASSERT_FALSE(files.empty()) << "no config files in " << kConfig;
  for (const std::string& name : files) {
    const auto loader = loaders.find(name);
    if (loader == loaders.end()) {
      ADD_FAILURE() << "config/" << name << ": no loader in this test (which program reads it?)";
      continue;
    }
    try {
      loader->second(kConfig + name);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "config/" << name << ": " << e.what();
    }
  }
}

TEST(ConfigFiles, EveryWorldAndArrayLoads) {
  const std::set<std::string> worlds = YamlFiles(kConfig + "worlds");
  EXPECT_GE(worlds.size(), 4u);
  for (const std::string& name : worlds) {
    try {
      const sim::World world = sim::LoadWorld(kConfig + "worlds/" + name);
      EXPECT_FALSE(world.people.empty()) << "config/worlds/" << name << ": nobody to find";
    } catch (const std::exception& e) {
      ADD_FAILURE() << "config/worlds/" << name << ": " << e.what();
    }
  }
  const std::set<std::string> arrays = YamlFiles(kConfig + "arrays");
  EXPECT_GE(arrays.size(), 1u);
  for (const std::string& name : arrays) {
    try {
      const common::MicArrayOptions array = common::LoadMicArray(kConfig + "arrays/" + name);
      EXPECT_GE(array.num_mics(), 2) << "config/arrays/" << name;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "config/arrays/" << name << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace sarmap
