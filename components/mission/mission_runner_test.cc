// A whole autonomous mission in simulated time: the simulated lab (Sales 2014's scenario 1)
// explored by the closed loop of simulator, depth-to-scan, SLAM and explorer, judged by the same
// metrics as the mission report.
#include "mission/mission_runner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <optional>

#include "log-tools/mission_metrics.h"

namespace sarmap {
namespace mission {
namespace {

class Collect : public MissionObserver {
 public:
  void OnTruth(double, const sim_truth_t& m) override { metrics.OnTruth(m.header.utime, m); }
  void OnFloor(double, const occupancy_grid_t& m) override { metrics.OnFloor(m.header.utime, m); }
  void OnMap(double, const occupancy_grid_t& m) override { metrics.OnMap(m.header.utime, m); }
  void OnExploreStatus(double, const explore_status_t& m) override {
    metrics.OnExploreStatus(m.header.utime, m);
  }
  void OnPeopleMap(double, const people_map_t& m) override { people = m; }
  void OnSoundMap(double, const sound_map_t&) override { ++sound_maps; }
  void OnAudio(double t_s, const audio_frame_t& m) override {
    ++audio_blocks;
    audio_in_order = audio_in_order && t_s >= last_audio_s;
    last_audio_s = t_s;
    audio_channels = m.num_channels;
  }
  logtools::MissionMetrics metrics;
  std::optional<people_map_t> people;
  int sound_maps = 0, audio_blocks = 0, audio_channels = 0;
  double last_audio_s = -1;
  bool audio_in_order = true;
};

MissionRunOptions Lab(const std::string& mode) {
  const std::string root = SARMAP_SOURCE_DIR;
  MissionRunOptions o;
  o.world = root + "/config/worlds/lab_lit.yaml";
  o.sim_config = root + "/config/sim.yaml";
  o.slam_config = root + "/config/slam_kinect_robot.yaml";
  o.explore_config = root + "/config/explore.yaml";
  o.depth_config = root + "/config/depth.yaml";
  o.mode = mode;
  o.duration_s = 240;
  return o;
}

TEST(MissionRunnerTest, FrontierExplorationMapsTheLabWithoutCollisionAndComesHome) {
  Collect collect;
  const MissionResult r = RunMission(Lab("frontier"), &collect);
  const logtools::MissionMetricsResult m = collect.metrics.Result();
  ASSERT_TRUE(m.mapped_fraction.has_value());
  std::printf("lab: %.1f %% of %.1f m^2 mapped, %d collisions, home after %.0f s, %.1f m driven\n",
              100 * *m.mapped_fraction, m.reachable_m2.value_or(0), r.collisions, r.home_after_s,
              r.distance_m);
  EXPECT_GE(*m.mapped_fraction, 0.9);
  EXPECT_EQ(r.collisions, 0);
  EXPECT_TRUE(r.came_home);
  EXPECT_TRUE(m.came_home);
  EXPECT_LT(r.simulated_s, 240);  // it ended by itself
}

TEST(MissionRunnerTest, TheSameSeedGivesTheSameMission) {
  MissionRunOptions o = Lab("frontier");
  o.duration_s = 30;
  const MissionResult a = RunMission(o), b = RunMission(o);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].truth_pose, b.samples[i].truth_pose)
        << "at " << a.samples[i].t_s << " s";
  }
}

// The final grids as PGMs that place themselves: a comment after the magic number gives the
// map frame's origin and cell size, and the pixels follow the header whole.
TEST(MissionRunnerTest, TheFinalGridsArePgmsWithTheirMapFrame) {
  MissionRunOptions o = Lab("frontier");
  o.duration_s = 5;
  o.explorer_map_pgm = ::testing::TempDir() + "/mission_explorer.pgm";
  o.slam_map_pgm = ::testing::TempDir() + "/mission_slam.pgm";
  RunMission(o);
  for (const std::string& path : {o.explorer_map_pgm, o.slam_map_pgm}) {
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in) << path;
    std::string magic, comment;
    std::getline(in, magic);
    std::getline(in, comment);
    EXPECT_EQ(magic, "P5");
    double origin_x_m = NAN, origin_y_m = NAN, resolution_m = NAN;
    ASSERT_EQ(
        std::sscanf(comment.c_str(), "# map frame: origin_x_m %lf origin_y_m %lf resolution_m %lf",
                    &origin_x_m, &origin_y_m, &resolution_m),
        3)
        << comment;
    EXPECT_NEAR(resolution_m, 0.05, 1e-9) << path;  // config/slam_kinect_robot.yaml
    // The robot starts at the map frame's origin, inside the grid.
    int width = 0, height = 0, max_value = 0;
    in >> width >> height >> max_value;
    in.get();
    EXPECT_LT(origin_x_m, 0.0);
    EXPECT_LT(origin_y_m, 0.0);
    EXPECT_GT(origin_x_m + width * resolution_m, 0.0);
    EXPECT_GT(origin_y_m + height * resolution_m, 0.0);
    EXPECT_EQ(max_value, 255);
    const std::string pixels((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
    EXPECT_EQ(pixels.size(), static_cast<size_t>(width) * height) << path;
  }
}

// Shared data the simulator cannot find (people photos, voice clips) is reported with the
// result, not silently replaced by grey bodies and silent voices.
TEST(MissionRunnerTest, MissingSharedDataIsAWarning) {
  MissionRunOptions o = Lab("frontier");
  o.duration_s = 1;
  o.sim_overrides = {"data_dir=/nonexistent/shared/data"};
  const MissionResult r = RunMission(o);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.front().find("/nonexistent"), std::string::npos) << r.warnings.front();
}

// The perception chain in the loop: people seen in the lab's first seconds are on the people
// map within 0.5 m of where they truly are (truth moved into the map frame by the start pose,
// as sarmap-log report does), and nobody is there who is not; the sound chain runs beside it.
TEST(MissionRunnerTest, PeopleSeenInTheLabAreOnThePeopleMapAndNobodyElse) {
  MissionRunOptions o = Lab("frontier");
  o.duration_s = 8;
  o.perception = true;
  o.sound = true;
  Collect collect;
  const MissionResult r = RunMission(o, &collect);
  const logtools::MissionMetricsResult m = collect.metrics.Result();
  ASSERT_TRUE(collect.people.has_value());
  ASSERT_FALSE(m.people.empty());
  std::vector<Eigen::Vector2d> truth_in_map;
  for (const auto& p : m.people) truth_in_map.push_back(p.map_m);
  std::vector<double> error_m;
  const std::vector<int> match =
      logtools::MatchPeople(truth_in_map, collect.people->people, 0.5, &error_m);
  int found = 0;
  std::vector<bool> used(collect.people->people.size(), false);
  for (size_t i = 0; i < match.size(); ++i) {
    if (match[i] < 0) continue;
    ++found;
    used[match[i]] = true;
    std::printf("%s found %.2f m off\n", m.people[i].name.c_str(), error_m[i]);
  }
  const int false_people = static_cast<int>(std::count(used.begin(), used.end(), false));
  std::printf("%d of %zu people found, %d false, %lld frames, %d sound maps\n", found,
              m.people.size(), false_people, static_cast<long long>(r.vision_frames),
              collect.sound_maps);
  EXPECT_GE(found, 1);
  EXPECT_EQ(false_people, 0);
  EXPECT_GT(r.vision_frames, 0);
  EXPECT_GT(collect.sound_maps, 0);
  // The array's audio reaches the observer (sarmap-mission-bench --audio-log), in time order.
  EXPECT_GT(collect.audio_blocks, 0);
  EXPECT_TRUE(collect.audio_in_order);
  EXPECT_EQ(collect.audio_channels, 4);  // the ReSpeaker of MissionRunOptions::sim_mic_array
}

}  // namespace
}  // namespace mission
}  // namespace sarmap
