#pragma once
// A whole autonomous mission in one process, in simulated time: the simulator core renders
// depth and odometry; the depth-to-scan converter, graph SLAM and the explorer run on them as
// sarmap-depth, sarmap-slam and sarmap-explore do over LCM, and the explorer's commands drive
// the simulated base. No LCM, no wall clock: a 10-minute mission runs as fast as the CPU
// allows and the same seed gives the same mission. The benchmark (sarmap-mission-bench) runs
// it over generated sites and compares exploration modes.
//
// With `perception`, people are found as in the live stack: sarmap-vision-people's detector
// and k-of-n confirmation on the simulator's RGB-D frames (PEOPLE_VISUAL), and
// sarmap-people-map's intake and map placing each detection with SLAM's POSE at its capture
// time (PEOPLE_MAP), from the same libraries and configuration files as those nodes. With
// `sound` too, the simulator's audio goes through sarmap-sound-localisation's DoaStream,
// sarmap-speech's SpeechStream and sarmap-sound-map's intake; PEOPLE_AUDIO and SOUND_MAP reach
// the people map, and the people heard on PEOPLE_MAP reach the explorer (mode sound_guided).

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "common/options.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/doa_t.hpp"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "slam/slam.h"

namespace sarmap {
namespace mission {

struct MissionRunOptions {
  std::string world;  // world YAML
  std::string sim_config = "config/sim.yaml";
  std::string slam_config = "config/slam_kinect_robot.yaml";
  std::string explore_config = "config/explore.yaml";
  std::string depth_config = "config/depth.yaml";
  std::string vision_config = "config/vision_people.yaml";
  std::string people_map_config = "config/people_map.yaml";
  std::string sound_localisation_config = "config/sound_localisation.yaml";
  std::string speech_config = "config/speech.yaml";
  std::string sound_map_config = "config/sound_map.yaml";
  // People from RGB-D (every camera frame) into the people map, placed with SLAM's POSE.
  bool perception = false;
  // With perception: the sound chain too (the simulator's audio, localisation, keyword
  // spotting, the sound map), its people heard into the people map and to the explorer.
  bool sound = true;
  std::string sim_mic_array = "respeaker4";  // the simulated robot's array (make demo's)
  std::string mode = "";                     // overrides explore.mode when not empty
  double duration_s = 600;
  double camera_rate_hz = 15;  // depth frames (and scans) per simulated second
  double map_period_s = 0;     // SLAM renders the map this often; 0: the SLAM file's map_period_s
  int64_t seed = 1;
  std::vector<std::string> sim_overrides;
  std::vector<std::string> explore_overrides;
  std::vector<std::string> slam_overrides;
  std::vector<std::string> depth_overrides;
  double report_period_s = 0;    // > 0: a MissionReport every this many simulated seconds
  std::string explorer_map_pgm;  // when set: the explorer's final grid (PGM with its map frame)
  std::string slam_map_pgm;      // when set: SLAM's final map (PGM with its map frame)
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

// The mission's state and cost so far, every report_period_s (long-mission figures: what grows
// with mission time). CPU seconds are cumulative since the start.
struct MissionReport {
  double t_s = 0;
  std::string state;
  double distance_m = 0;
  double cpu_s = 0, slam_cpu_s = 0, explore_cpu_s = 0, vision_cpu_s = 0, people_map_cpu_s = 0,
         sound_cpu_s = 0;
  double rss_mb = 0;   // the process's resident memory
  double heap_mb = 0;  // of which the allocator hands out (in use, every arena and mmap)
  slam::Slam::MemoryUsage slam_memory;       // of which SLAM's data, by part
  int64_t slam_nodes = 0, slam_submaps = 0;  // live (untrimmed)
  int64_t slam_nodes_kept = 0;               // live nodes without a live submap, kept for a client
  // Finished submaps kept by trimming for their new area / for new obstacles only (cumulative).
  int64_t slam_submaps_kept_area = 0, slam_submaps_kept_obstacles = 0;
  int64_t slam_optimisations = 0, slam_loop_closures = 0;
  double slam_optimise_s = 0;  // cumulative time in the global optimisation
  double slam_map_s = 0;       // cumulative time drawing MAP (Slam::DrawMap)
  int64_t slam_map_draws = 0, slam_map_redraws = 0;  // MAPs drawn; of them drawn from every node
  int people_on_map = 0, sound_sources = 0;
  int64_t detections_without_pose = 0;
};

struct MissionResult {
  double simulated_s = 0;
  double cpu_s = 0;             // whole process
  double explore_cpu_s = 0;     // the explorer alone
  double slam_cpu_s = 0;        // depth-to-scan, SLAM, its map, POSE covariance and anchors
  double vision_cpu_s = 0;      // decoding, detection and confirmation of the RGB-D frames
  double people_map_cpu_s = 0;  // the people map's intake and map
  double sound_cpu_s = 0;       // localisation, speech and the sound map (not the audio simulation)
  int64_t heard_calls = 0;      // PEOPLE_AUDIO messages (keywords with a direction)
  int64_t vision_frames = 0;
  int64_t detections_without_pose = 0;  // dropped by the people map (no POSE near their time)
  double distance_m = 0;
  int collisions = 0;
  std::vector<std::string> contacts;  // each collision: when, where (world frame) and against what
  // The base's closest approach to anything the simulator's collision model holds (walls, boxes,
  // table legs, people), in metres between the base's edge and the obstacle: the margin that
  // was left (0 at a contact), every simulation step.
  double closest_gap_m = std::numeric_limits<double>::infinity();
  std::string closest_gap_what;  // when, where and against what
  int recoveries = 0;
  int looks = 0;  // the explorer's turns to look at unseen space on its arc
  bool came_home = false;
  double home_after_s = -1;
  std::string final_state;
  std::vector<MissionSample> samples;
  // SLAM's trail as its final graph puts it (every scan: t_s, x, y, yaw in the map frame): where
  // the loop closures moved the poses that placed the detections.
  std::vector<Eigen::Vector4d> final_slam_trail;
  std::vector<MissionReport> reports;  // every report_period_s
  // The simulator's warnings (people photos or voice clips not found: a mission that sees grey
  // bodies and hears silent voices).
  std::vector<std::string> warnings;
};

// Called for every message the simulator emits (truth, floor), the SLAM map when it is
// rendered, the explorer's status, SLAM's POSE and the people map, so that metrics can be
// computed in the same pass.
// Times are simulated seconds since the start.
struct MissionObserver {
  virtual ~MissionObserver() = default;
  virtual void OnTruth(double /*t_s*/, const sarmap::sim_truth_t& /*truth*/) {}
  virtual void OnFloor(double /*t_s*/, const sarmap::occupancy_grid_t& /*floor*/) {}
  virtual void OnMap(double /*t_s*/, const sarmap::occupancy_grid_t& /*map*/) {}
  virtual void OnExploreStatus(double /*t_s*/, const sarmap::explore_status_t& /*status*/) {}
  // SLAM's POSE of every accepted scan.
  virtual void OnPose(double /*t_s*/, const sarmap::pose_t& /*pose*/) {}
  // PEOPLE_VISUAL (perception on): each confirmed frame as the people map takes it.
  virtual void OnSeen(double /*t_s*/, const sarmap::people_detections_t& /*seen*/) {}
  // PEOPLE_MAP (perception on): after every input that changed it, and every publish_period_s.
  virtual void OnPeopleMap(double /*t_s*/, const sarmap::people_map_t& /*people*/) {}
  // SOUND_MAP (perception and sound on), every publish_period_s of message time.
  virtual void OnSoundMap(double /*t_s*/, const sarmap::sound_map_t& /*sources*/) {}
  // DOA_MAP (perception and sound on): the localiser's directions as the sound map takes them;
  // DOA: its every-bin directions, as the speech beams take them.
  virtual void OnDoaMap(double /*t_s*/, const sarmap::doa_t& /*doa*/) {}
  virtual void OnDoa(double /*t_s*/, const sarmap::doa_t& /*doa*/) {}
  // PEOPLE_AUDIO (keywords with a direction) and SLAM_ANCHORS, as the sound map takes them.
  virtual void OnHeard(double /*t_s*/, const sarmap::people_detections_t& /*heard*/) {}
  virtual void OnSlamAnchors(double /*t_s*/, const sarmap::slam_anchors_t& /*anchors*/) {}
  // AUDIO (perception and sound on): each block of the simulated array, before the sound chain.
  virtual void OnAudio(double /*t_s*/, const sarmap::audio_frame_t& /*audio*/) {}
};

// Runs one mission. Throws on bad configuration (OptionsError, WorldError).
MissionResult RunMission(const MissionRunOptions& options, MissionObserver* observer = nullptr,
                         const std::function<void(double t_s)>& progress = nullptr);

}  // namespace mission
}  // namespace sarmap
