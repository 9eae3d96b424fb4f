#include "sim/site_generator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sim/floor_plan.h"
#include "sim/robot.h"

namespace sarmap {
namespace sim {
namespace {

SiteOptions Seed(int64_t seed) {
  SiteOptions o;
  o.seed = seed;
  return o;
}

// Every field the world file holds, compared exactly.
void ExpectSameWorld(const World& a, const World& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.lights_on, b.lights_on);
  EXPECT_EQ(a.ceiling_height_m, b.ceiling_height_m);
  ASSERT_EQ(a.walls.size(), b.walls.size());
  for (size_t i = 0; i < a.walls.size(); ++i) {
    EXPECT_EQ(a.walls[i].from, b.walls[i].from);
    EXPECT_EQ(a.walls[i].to, b.walls[i].to);
    EXPECT_EQ(a.walls[i].height_m, b.walls[i].height_m);
    EXPECT_EQ(a.walls[i].thickness_m, b.walls[i].thickness_m);
    EXPECT_EQ(a.walls[i].colour.r, b.walls[i].colour.r);
  }
  ASSERT_EQ(a.boxes.size(), b.boxes.size());
  for (size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_EQ(a.boxes[i].name, b.boxes[i].name);
    EXPECT_EQ(a.boxes[i].centre, b.boxes[i].centre);
    EXPECT_EQ(a.boxes[i].yaw_rad, b.boxes[i].yaw_rad);
    EXPECT_EQ(a.boxes[i].size_m, b.boxes[i].size_m);
    EXPECT_EQ(a.boxes[i].colour.g, b.boxes[i].colour.g);
  }
  ASSERT_EQ(a.tables.size(), b.tables.size());
  for (size_t i = 0; i < a.tables.size(); ++i) {
    EXPECT_EQ(a.tables[i].centre, b.tables[i].centre);
    EXPECT_EQ(a.tables[i].yaw_rad, b.tables[i].yaw_rad);
    EXPECT_EQ(a.tables[i].size_m, b.tables[i].size_m);
    EXPECT_EQ(a.tables[i].height_m, b.tables[i].height_m);
  }
  ASSERT_EQ(a.people.size(), b.people.size());
  for (size_t i = 0; i < a.people.size(); ++i) {
    EXPECT_EQ(a.people[i].id, b.people[i].id);
    EXPECT_EQ(a.people[i].name, b.people[i].name);
    EXPECT_EQ(a.people[i].position, b.people[i].position);
    EXPECT_EQ(a.people[i].yaw_rad, b.people[i].yaw_rad);
    EXPECT_EQ(a.people[i].posture, b.people[i].posture);
    EXPECT_EQ(a.people[i].height_m, b.people[i].height_m);
  }
  ASSERT_EQ(a.sources.size(), b.sources.size());
  for (size_t i = 0; i < a.sources.size(); ++i) {
    EXPECT_EQ(a.sources[i].name, b.sources[i].name);
    EXPECT_EQ(a.sources[i].kind, b.sources[i].kind);
    EXPECT_EQ(a.sources[i].person_id, b.sources[i].person_id);
    EXPECT_EQ(a.sources[i].position, b.sources[i].position);
    EXPECT_EQ(a.sources[i].clips, b.sources[i].clips);
    EXPECT_EQ(a.sources[i].level_db_spl, b.sources[i].level_db_spl);
    EXPECT_EQ(a.sources[i].start_s, b.sources[i].start_s);
    EXPECT_EQ(a.sources[i].every_s, b.sources[i].every_s);
    EXPECT_EQ(a.sources[i].duration_s, b.sources[i].duration_s);
    EXPECT_EQ(a.sources[i].hum_hz, b.sources[i].hum_hz);
  }
  EXPECT_EQ(a.acoustics.rt60_s, b.acoustics.rt60_s);
  EXPECT_EQ(a.acoustics.ambient_noise_db_spl, b.acoustics.ambient_noise_db_spl);
  EXPECT_EQ(a.robot.pose, b.robot.pose);
  EXPECT_EQ(a.robot.path.size(), b.robot.path.size());
}

TEST(SiteGeneratorTest, SameSeedSameWorldFileOtherSeedOtherWorld) {
  const std::string a = WorldToYaml(GenerateSite(Seed(3)), SiteHeader(Seed(3)));
  EXPECT_EQ(a, WorldToYaml(GenerateSite(Seed(3)), SiteHeader(Seed(3))));
  EXPECT_NE(WorldToYaml(GenerateSite(Seed(3))), WorldToYaml(GenerateSite(Seed(4))));
  EXPECT_NE(a.find("seed: 3"), std::string::npos);  // the header names the options
  EXPECT_EQ(a.rfind("# Generated incident site", 0), 0u);
}

// Seeds 1..20 with the default options: the building, its rooms and their reachability, people
// clear of furniture and on (or within 1 m of) reachable floor, a hidden person, the round trip
// through the world file.
TEST(SiteGeneratorTest, TwentySeedsGiveBuildingsWhoseRoomsAreAllReachable) {
  for (int64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const SiteOptions options = Seed(seed);
    const Site site = GenerateSiteLayout(options);
    const World& w = site.world;
    EXPECT_GE(site.size_m.prod(), 150.0);
    EXPECT_GE(site.rooms_without_corridor(), 4);
    const GridMap floor = ReachableFloor(w, options.robot_radius_m);
    const GridMap floor_with_people = ReachableFloor(w, options.robot_radius_m, 0.05, true);
    const double reachable = FloorArea(floor);
    EXPECT_GE(reachable, 0.7 * site.size_m.prod());
    EXPECT_GE(reachable, 150.0);  // the default 200 m^2 building leaves at least 150 m^2 to cover
    for (const SiteRoom& room : site.rooms) {
      EXPECT_EQ(CellAt(floor, room.Centre()), 0) << room.name;
      EXPECT_EQ(CellAt(floor_with_people, room.Centre()), 0) << room.name << " (people in the way)";
    }
    EXPECT_GE(static_cast<int>(w.people.size()), options.people_min);
    EXPECT_LE(static_cast<int>(w.people.size()), options.people_max);
    EXPECT_GE(static_cast<int>(site.hidden_people.size()), options.hidden_min);
    const std::vector<Obstacle> obstacles = CollisionObstacles(w, false);
    for (const Person& p : w.people) {
      SCOPED_TRACE(p.name);
      EXPECT_FALSE(CircleCollides(p.position, 0.2, obstacles));
      // Within 1 m of reachable floor: search the cells around the person.
      bool near = false;
      for (double dx = -1.0; dx <= 1.0 && !near; dx += 0.05) {
        for (double dy = -1.0; dy <= 1.0 && !near; dy += 0.05) {
          near =
              std::hypot(dx, dy) <= 1.0 && CellAt(floor, p.position + Eigen::Vector2d(dx, dy)) == 0;
        }
      }
      EXPECT_TRUE(near);
    }
    for (int id : site.hidden_people) {
      bool calls = false;
      for (const SoundSource& s : w.sources) calls = calls || s.person_id == id;
      EXPECT_TRUE(calls) << "hidden person " << id << " is silent";
    }
    EXPECT_FALSE(CircleCollides(w.robot.pose.head<2>(), options.robot_radius_m,
                                CollisionObstacles(w, true)));
    const std::string yaml = WorldToYaml(w);
    const World back = ParseWorld(yaml, "site.yaml");
    ExpectSameWorld(w, back);
    EXPECT_EQ(WorldToYaml(back), yaml);
    if (seed <= 6) std::printf("%s\n", SiteSummary(site, reachable).c_str());
  }
}

TEST(SiteGeneratorTest, OptionsShapeTheSite) {
  SiteOptions o = Seed(5);
  o.floor_area_m2 = 400;
  o.min_rooms = 10;
  o.hidden_min = o.hidden_max = 3;
  o.lighting = "dark";
  const Site big = GenerateSiteLayout(o);
  EXPECT_NEAR(big.size_m.prod(), 400, 10);
  EXPECT_GE(big.rooms_without_corridor(), 10);
  EXPECT_EQ(big.hidden_people.size(), 3u);
  EXPECT_FALSE(big.world.lights_on);
  o = Seed(5);
  o.floor_area_m2 = 60;
  o.hidden_min = o.hidden_max = 0;
  o.people_min = o.people_max = 2;
  o.lighting = "lit";
  const Site small = GenerateSiteLayout(o);
  EXPECT_NEAR(small.size_m.prod(), 60, 3);
  EXPECT_GE(small.rooms_without_corridor(), 4);
  EXPECT_TRUE(small.hidden_people.empty());
  EXPECT_EQ(small.world.people.size(), 2u);
  EXPECT_TRUE(small.world.lights_on);
  o.door_width_min_m = 0.5;  // a robot of 0.5 m would not fit
  EXPECT_THROW(GenerateSite(o), common::OptionsError);
}

TEST(WorldToYamlTest, ShippedWorldsSurviveTheRoundTrip) {
  for (const char* name :
       {"lab_lit.yaml", "lab_dark.yaml", "corridor_glass.yaml", "open_area_sound.yaml"}) {
    SCOPED_TRACE(name);
    const World w = LoadWorld(std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + name);
    const std::string yaml = WorldToYaml(w);
    const World back = ParseWorld(yaml, name);
    EXPECT_EQ(WorldToYaml(back), yaml);
    EXPECT_EQ(back.robot.path, w.robot.path);
  }
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
