#pragma once
// Generated incident sites: a building of a given floor area laid out from a seed, for the
// autonomous-search benchmark (many sites, each the same on every machine).
//
// Layout (building frame: x along the long side from the south-west corner, metres):
//   - a rectangle L x D with L / D in [1.1, 1.7] and L * D = floor_area_m2 (centre lines of
//     the outer walls);
//   - a corridor along x, rooms on both sides (one side when the building is too shallow for
//     two rows of rooms at least 2.3 m deep), optionally a hall across the east end;
//   - every room opens onto the corridor (the hall too) through a door of
//     door_width_[min,max]_m; some neighbouring rooms share a second door;
//   - furniture against the walls (cabinets, shelves, beds, sofas, chairs), tables, machines,
//     debris (small boxes, low rubble, fallen shelves) anywhere; nothing in front of a door,
//     on a room's centre or at the robot's start;
//   - hidden people: each sits or stands in a room corner behind a tall screen placed across
//     the corner, so that the camera cannot see them but the microphones hear them call;
//   - sound: voices for the hidden people and some others, an alarm, machine noise with hum;
//   - acoustics: RT60 from Sabine's formula for the mean room (see site_generator.cc).
// Reachability is checked with ReachableFloor() (the robot's own collision model): every
// room's centre must be reachable from the start, also with the people as obstacles; debris
// and then furniture that cut a room off are removed (last placed first), and an attempt that
// still fails starts over from a seed derived from (seed, attempt).
//
// Random numbers: std::mt19937_64 (its output sequence is fixed by the standard) turned into
// uniforms by the generator's own code, so a seed gives the same site with any standard
// library; coordinates are rounded to millimetres and angles to whole degrees.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/options.h"
#include "sim/world.h"

namespace sarmap {
namespace sim {

struct SiteOptions {
  int64_t seed = 1;
  double floor_area_m2 = 200.0;  // building footprint (outer walls' centre lines)
  int min_rooms = 4;             // rooms besides the corridor
  double corridor_width_min_m = 1.5;
  double corridor_width_max_m = 2.0;
  double door_width_min_m = 0.9;
  double door_width_max_m = 1.2;
  double wall_height_min_m = 2.5;
  double wall_height_max_m = 2.7;
  int furniture_min_per_room = 2;  // plus one per 12 m^2 of room
  int furniture_max_per_room = 4;
  int debris_min = 3;
  int debris_max = 7;
  int people_min = 3;
  int people_max = 6;
  int hidden_min = 1;  // people hidden behind a screen in a corner (heard, not seen)
  int hidden_max = 2;
  double voice_probability = 0.5;  // for people in view; hidden people always call
  double alarm_probability = 0.7;
  double music_probability = 0.6;  // a radio playing in one room
  int machines_min = 1;
  int machines_max = 2;
  std::string lighting = "seed";  // lit, dark, or seed (dark with dark_probability)
  double dark_probability = 0.5;
  double robot_radius_m = 0.25;  // for the reachability checks
  double passage_margin_m = 0.1;  // rooms must be reachable with this much room on each side
  int max_attempts = 20;
  template <class V>
  void Visit(V& v) {
    v("seed", seed, "random seed: the same seed gives the same site");
    v("floor_area_m2", floor_area_m2, "building footprint, 60..600 m^2", InRange(60, 600));
    v("min_rooms", min_rooms, "at least this many rooms besides the corridor", InRange(4, 24));
    v("corridor_width_min_m", corridor_width_min_m, "corridor width range");
    v("corridor_width_max_m", corridor_width_max_m, "");
    v("door_width_min_m", door_width_min_m, "door gap range (robot diameter + 0.3 m at least)");
    v("door_width_max_m", door_width_max_m, "");
    v("wall_height_min_m", wall_height_min_m, "wall (and ceiling) height range", InRange(2.0, 4.0));
    v("wall_height_max_m", wall_height_max_m, "");
    v("furniture_min_per_room", furniture_min_per_room,
      "furniture items per room (plus one per 12 m^2)");
    v("furniture_max_per_room", furniture_max_per_room, "");
    v("debris_min", debris_min, "debris items in the building");
    v("debris_max", debris_max, "");
    v("people_min", people_min, "people in the building");
    v("people_max", people_max, "");
    v("hidden_min", hidden_min, "people hidden behind a screen in a room corner (only heard)");
    v("hidden_max", hidden_max, "");
    v("voice_probability", voice_probability,
      "chance that a person in view calls (hidden people always do)", InRange(0, 1));
    v("alarm_probability", alarm_probability,
      "chance of an alarm sounding in the corridor (a siren or a beeper)", InRange(0, 1));
    v("music_probability", music_probability, "chance of a radio playing music in one room",
      InRange(0, 1));
    v("machines_min", machines_min, "machines humming in rooms");
    v("machines_max", machines_max, "");
    v("lighting", lighting, "lit, dark, or seed (dark with dark_probability)",
      OneOf({"lit", "dark", "seed"}));
    v("dark_probability", dark_probability, "lighting: seed: chance that the lights are off",
      InRange(0, 1));
    v("robot_radius_m", robot_radius_m, "robot radius for the reachability checks",
      InRange(0.1, 0.5));
    v("passage_margin_m", passage_margin_m,
      "every room must be reachable by a robot this much wider on each side (debris never leaves a squeeze)");
    v("max_attempts", max_attempts, "layouts tried before giving up", AtLeast(1));
  }
  void Validate(common::Validator& check) const {
    check.That(corridor_width_min_m >= 2 * robot_radius_m + 0.5, "corridor_width_min_m",
               "must leave 0.5 m beside the robot's diameter");
    check.That(corridor_width_max_m >= corridor_width_min_m && corridor_width_max_m <= 3.0,
               "corridor_width_max_m", "must be in [corridor_width_min_m, 3]");
    check.That(door_width_min_m >= 2 * robot_radius_m + 0.3, "door_width_min_m",
               "must exceed the robot's diameter by 0.3 m");
    check.That(door_width_max_m >= door_width_min_m && door_width_max_m <= 1.6, "door_width_max_m",
               "must be in [door_width_min_m, 1.6]");
    check.That(wall_height_max_m >= wall_height_min_m && wall_height_max_m <= 4.0,
               "wall_height_max_m", "must be in [wall_height_min_m, 4]");
    check.That(furniture_min_per_room >= 0 && furniture_max_per_room >= furniture_min_per_room &&
                   furniture_max_per_room <= 10,
               "furniture_max_per_room", "need 0 <= min <= max <= 10");
    check.That(debris_min >= 0 && debris_max >= debris_min && debris_max <= 40, "debris_max",
               "need 0 <= min <= max <= 40");
    check.That(people_min >= 0 && people_max >= people_min && people_max <= 20, "people_max",
               "need 0 <= min <= max <= 20");
    check.That(hidden_min >= 0 && hidden_max >= hidden_min && hidden_max <= 6, "hidden_max",
               "need 0 <= min <= max <= 6");
    check.That(hidden_min <= people_min, "hidden_min", "must be <= people_min");
    check.That(machines_min >= 0 && machines_max >= machines_min && machines_max <= 6,
               "machines_max", "need 0 <= min <= max <= 6");
    check.That(passage_margin_m >= 0 && 2 * (robot_radius_m + passage_margin_m) < door_width_min_m,
               "passage_margin_m", "must be >= 0 and leave the narrowest door passable");
  }
};

struct SiteRoom {
  std::string name;
  Eigen::Vector2d min = Eigen::Vector2d::Zero(),
                  max = Eigen::Vector2d::Zero();  // wall centre lines
  bool corridor = false;
  Eigen::Vector2d Centre() const { return 0.5 * (min + max); }
  double Area() const { return (max - min).prod(); }
};

// A generated site: the world and what the generator knows about it.
struct Site {
  World world;
  std::vector<SiteRoom> rooms;                       // the corridor first, then the rooms
  Eigen::Vector2d size_m = Eigen::Vector2d::Zero();  // building L x D (outer walls' centre lines)
  std::vector<int> hidden_people;                    // person ids of the people behind screens
  int attempt = 0;                                   // layouts rejected before this one
  int rooms_without_corridor() const;
};

// Throws std::runtime_error when no attempt gives a site that passes the checks (options
// asking for more than fits, e.g. 24 rooms in 60 m^2).
Site GenerateSiteLayout(const SiteOptions& options);
World GenerateSite(const SiteOptions& options);

// A comment block for the top of a generated world file: generator, seed and every option.
std::string SiteHeader(const SiteOptions& options);
// One paragraph: floor area, rooms, reachable floor, people (posture, hidden), sound sources,
// lighting. `reachable_m2` from FloorArea(ReachableFloor(...)).
std::string SiteSummary(const Site& site, double reachable_m2);

}  // namespace sim
}  // namespace sarmap
