#include "tools/shipped_configs.h"

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
#include "slam/slam_node_options.h"
#include "sound_localisation/doa_stream.h"
#include "handheld_sound_map/handheld_sound_map_messages.h"
#include "sound_map/sound_map_messages.h"
#include "speech/speech_messages.h"
#include "teleop/teleop.h"
#include "viewer/viewer_options.h"
#include "vision_people/vision_people_options.h"

namespace sarmap {

namespace {

// `required`: what the program's command line must add for the file to validate (e.g. the
// recording to read); the table shows the file's own values.
template <class Options>
ShippedConfig Config(std::string file, std::vector<std::string> required = {}) {
  ShippedConfig config;
  config.file = std::move(file);
  config.load = [required](const std::string& path) {
    common::LoadOptions<Options>(path, required);
  };
  config.markdown = [](const std::string& path) {
    return common::OptionsToMarkdown(common::ReadOptions<Options>(path, {}));
  };
  return config;
}

}  // namespace

const std::vector<ShippedConfig>& ShippedConfigs() {
  static const std::vector<ShippedConfig> configs = {
      Config<audio::CaptureOptions>("audio_capture.yaml", {"file=recording.wav"}),  // --file
      Config<depth::DepthNodeOptions>("depth.yaml"),
      Config<explore::ExploreNodeOptions>("explore.yaml"),
      Config<sound_map::HandheldSoundMapOptions>("handheld_sound_map.yaml"),
      Config<mic_calibrate::MicCalibrateOptions>("mic_calibrate.yaml"),
      Config<people_map::PeopleMapNodeOptions>("people_map.yaml"),
      Config<procman::ProcmanOptions>("procman.yaml"),
      Config<logtools::RecordProfileOptions>("record_long.yaml"),
      Config<rgbd_odometry::RgbdOdometryNodeOptions>("rgbd_odometry.yaml"),
      Config<common::RobotOptions>("robot.yaml"),
      Config<logtools::RosbagOptions>("rosbag.yaml"),
      Config<sim::SimOptions>("sim.yaml"),
      Config<sim::SiteOptions>("site.yaml"),
      Config<slam::SlamNodeOptions>("slam.yaml"),
      Config<slam::SlamNodeOptions>("slam_kinect_robot.yaml"),
      Config<sound::SoundLocalisationOptions>("sound_localisation.yaml"),
      Config<sound_map::SoundMapNodeOptions>("sound_map.yaml"),
      Config<speech::SpeechNodeOptions>("speech.yaml"),
      Config<teleop::TeleopOptions>("teleop.yaml"),
      Config<viewer::ViewerNodeOptions>("viewer.yaml"),
      Config<vision_people::VisionPeopleOptions>("vision_people.yaml"),
  };
  return configs;
}

}  // namespace sarmap
