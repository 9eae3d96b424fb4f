#include "sim/world.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <filesystem>
#include <set>

namespace sarmap {
namespace sim {
namespace {

TEST(WorldTest, ShippedWorldsLoad) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(SARMAP_SOURCE_DIR) + "/config/worlds")) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const World world = LoadWorld(entry.path().string());
    EXPECT_FALSE(world.name.empty());
    EXPECT_FALSE(world.sources.empty());
    ++count;
  }
  EXPECT_GE(count, 4);
  const World lab = LoadWorld(std::string(SARMAP_SOURCE_DIR) + "/config/worlds/lab_lit.yaml");
  EXPECT_EQ(lab.people.size(), 3u);
  EXPECT_TRUE(lab.lights_on);
  const World dark = LoadWorld(std::string(SARMAP_SOURCE_DIR) + "/config/worlds/lab_dark.yaml");
  EXPECT_FALSE(dark.lights_on);
  const World corridor = LoadWorld(std::string(SARMAP_SOURCE_DIR) + "/config/worlds/corridor_glass.yaml");
  int glass = 0;
  for (const Wall& w : corridor.walls) glass += w.glass;
  EXPECT_GE(glass, 2);
  EXPECT_EQ(corridor.people.size(), 2u);
}

// Every shipped world carries an emitter of every class (voice, music, alarm, machinery), so
// the sound maps can be scored per class; beepers and the siren parse and write back.
TEST(WorldTest, ShippedWorldsCarryEveryClassOfSource) {
  for (const auto& entry : std::filesystem::directory_iterator(std::string(SARMAP_SOURCE_DIR) + "/config/worlds")) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const World world = LoadWorld(entry.path().string());
    std::set<SourceKind> kinds;
    for (const SoundSource& s : world.sources) kinds.insert(s.kind);
    EXPECT_EQ(kinds.size(), 4u);
    const World again = ParseWorld(WorldToYaml(world), "again");
    ASSERT_EQ(again.sources.size(), world.sources.size());
    for (size_t i = 0; i < world.sources.size(); ++i) {
      EXPECT_EQ(again.sources[i].tone_hz, world.sources[i].tone_hz);
      EXPECT_EQ(again.sources[i].beep_period_s, world.sources[i].beep_period_s);
    }
  }
  EXPECT_THROW(ParseWorld("name: x\nsources:\n  - {kind: noise, position: [1, 1, 1], tone_hz: 3000}\n", "x"),
               WorldError);
}

// The robot must be able to drive its scripted path: a person standing on it blocks the robot
// for the rest of the mission (the simulator stops it at people, as a real robot would).
TEST(WorldTest, ScriptedPathsKeepClearOfPeople) {
  constexpr double kClearanceM = 0.6;  // robot radius 0.25 m + a person + a margin
  for (const char* name : {"lab_lit.yaml", "lab_dark.yaml", "corridor_glass.yaml", "open_area_sound.yaml"}) {
    const World w = LoadWorld(std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + name);
    std::vector<Eigen::Vector2d> path = {w.robot.pose.head<2>()};
    path.insert(path.end(), w.robot.path.begin(), w.robot.path.end());
    if (w.robot.path_loop) path.push_back(path.front());
    for (size_t i = 1; i < path.size(); ++i) {
      const Eigen::Vector2d a = path[i - 1], ab = path[i] - path[i - 1];
      for (const Person& p : w.people) {
        const double t = ab.squaredNorm() > 0 ? std::clamp((p.position - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
        EXPECT_GE((a + t * ab - p.position).norm(), kClearanceM)
            << name << ": " << p.name << " stands on the path leg " << i;
      }
    }
  }
}

// Every person of a scenario comes, somewhere along the scripted path, within the Kinect's depth
// range (4.6 m) and horizontal field of view (58 deg) of a robot driving forward — occlusion
// aside (the lab's hidden caller is hidden by a cabinet, not by distance). A person never in
// range cannot be found by sight, whatever the detector.
TEST(WorldTest, EveryPersonComesIntoDepthRangeAlongThePath) {
  constexpr double kRangeM = 4.5, kHalfFovRad = 29.0 * M_PI / 180;
  for (const char* name : {"lab_lit.yaml", "lab_dark.yaml", "corridor_glass.yaml"}) {
    const World w = LoadWorld(std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + name);
    std::vector<Eigen::Vector2d> path = {w.robot.pose.head<2>()};
    path.insert(path.end(), w.robot.path.begin(), w.robot.path.end());
    for (const Person& p : w.people) {
      bool seen = false;
      for (size_t i = 1; i < path.size() && !seen; ++i) {
        const Eigen::Vector2d ab = path[i] - path[i - 1];
        if (ab.norm() < 1e-6) continue;
        const double heading = std::atan2(ab.y(), ab.x());
        for (double t = 0; t <= 1.0 && !seen; t += 0.01) {
          const Eigen::Vector2d to = p.position - (path[i - 1] + t * ab);
          const double bearing = std::remainder(std::atan2(to.y(), to.x()) - heading, 2 * M_PI);
          seen = to.norm() < kRangeM && std::abs(bearing) < kHalfFovRad;
        }
      }
      EXPECT_TRUE(seen) << name << ": " << p.name << " is never within the depth camera's range and view";
    }
  }
}

TEST(WorldTest, SourceTakesThePersonsMouth) {
  const World w = ParseWorld(R"(
people:
  - {name: a, position: [1, 2], posture: standing, height_m: 1.8}
sources:
  - {name: v, kind: voice, person: a, clips: ["espeak:help"]}
)", "w.yaml");
  ASSERT_EQ(w.sources.size(), 1u);
  EXPECT_EQ(w.sources[0].person_id, 1);
  EXPECT_NEAR(w.sources[0].position.x(), 1.0, 1e-12);
  EXPECT_GT(w.sources[0].position.z(), 1.5);
}

// Each bad file names the file, the line and the key.
struct BadCase {
  const char* text;
  const char* where;  // "file:line"
  const char* key;
};

TEST(WorldTest, BadFilesNameFileLineAndKey) {
  const BadCase cases[] = {
      {"name: x\nwalls:\n  - {from: [0, 0], to: [1, 0], hieght_m: 2}\n", "bad.yaml:3:", "walls[0].hieght_m: unknown key"},
      {"people:\n  - name: a\n    position: [1, 2]\n    posture: crouching\n", "bad.yaml:4:", "people[0].posture"},
      {"boxes:\n  - {centre: [1, 2], size_m: [1, 1]}\n", "bad.yaml:2:", "boxes[0].size_m"},
      {"sources:\n  - {kind: voice, person: nobody, clips: [a.wav]}\n", "bad.yaml:2:", "sources[0].person"},
      {"tables:\n  - {centre: [1, 2], size_m: [1, 1], height_m: -1}\n", "bad.yaml:2:", "tables[0].height_m"},
      {"lights_on: maybe\n", "bad.yaml:1:", "lights_on"},
      {"robot:\n  start: [0, 0, 0]\n  path: [[1, 2], [3]]\n", "bad.yaml:3:", "robot.path[1]"},
      {"walls:\n  - {to: [1, 0]}\n", "bad.yaml:2:", "walls[0].from: required key missing"},
      {"acoustics:\n  rt60_s: 9\n", "bad.yaml:2:", "acoustics.rt60_s"},
      {"walls: [\n", "bad.yaml:", "YAML syntax error"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      ParseWorld(c.text, "bad.yaml");
      ADD_FAILURE() << "accepted a bad world";
    } catch (const WorldError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(c.where), std::string::npos) << what;
      EXPECT_NE(what.find(c.key), std::string::npos) << what;
    }
  }
}

TEST(WorldTest, MissingFileIsAnError) {
  EXPECT_THROW(LoadWorld("/nonexistent/world.yaml"), WorldError);
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
