#pragma once
// The simulated world: static geometry (walls, glass, furniture boxes, tables), people,
// sound emitters, room acoustics and the robot's start pose / scripted path, loaded from a
// world YAML file (config/worlds/*.yaml; reference in components/sim/WORLD_FORMAT.md).
//
// Frames: everything is in the `map` frame, x/y on the floor, z up, metres and radians.

#include <Eigen/Core>

#include <array>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sarmap {
namespace sim {

// A world file that cannot be used: the message names file, line and key.
class WorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Rgb {
  float r = 0.7f, g = 0.7f, b = 0.7f;  // albedo in [0, 1]
};

// A straight wall segment from `from` to `to` (floor plane), `height_m` tall. Glass panels
// are walls with glass = true: no infrared return, a faint tint in colour.
struct Wall {
  std::string name;
  Eigen::Vector2d from = Eigen::Vector2d::Zero(), to = Eigen::Vector2d::Zero();
  double height_m = 2.5;
  double thickness_m = 0.1;
  double base_m = 0.0;  // bottom edge above the floor
  Rgb colour{0.85f, 0.84f, 0.80f};
  bool glass = false;
};

// An oriented box standing on the floor (cabinet, shelf, server rack, chair block...).
struct Box {
  std::string name;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  Eigen::Vector3d size_m{0.5, 0.5, 0.5};  // along its x, y and height
  double base_m = 0.0;
  Rgb colour{0.5f, 0.4f, 0.3f};
};

// A table: a top of `top_thickness_m` at `height_m` on four legs; open space beneath.
struct Table {
  std::string name;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  Eigen::Vector2d size_m{1.2, 0.8};
  double height_m = 0.75;
  double top_thickness_m = 0.04;
  double leg_width_m = 0.05;
  Rgb colour{0.55f, 0.42f, 0.30f};
};

enum class Posture { kStanding = 1, kSitting = 2, kLying = 3 };

struct Person {
  int id = 0;
  std::string name;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // floor point below the person
  double yaw_rad = 0.0;                                 // facing direction
  Posture posture = Posture::kStanding;
  double height_m = 1.75;                               // standing height
  int appearance = -1;                                  // index into the appearances, -1 = by id
  // Mouth position in the map frame (source position of this person's voice).
  Eigen::Vector3d Mouth() const;
};

enum class SourceKind { kVoice = 1, kMusic = 2, kAlarm = 3, kNoise = 4 };

// A sound emitter. Active during events: at start_s, start_s + every_s, ... (every_s = 0:
// once), each lasting duration_s (voices: the clip's length; 0 for music/alarm/noise: until
// stop_s). A continuous voice plays its clips back to back with gap_s between them.
struct SoundSource {
  int id = 0;
  std::string name;
  SourceKind kind = SourceKind::kVoice;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int person_id = -1;              // the speaking person (position from the person's mouth)
  double level_db_spl = 65.0;      // RMS sound pressure level at 1 m
  std::vector<std::string> clips;  // voices: "espeak:<phrase>" or a path under data_dir
  double start_s = 0.0;
  double every_s = 0.0;
  double duration_s = 0.0;
  double stop_s = std::numeric_limits<double>::infinity();
  bool continuous = false;
  double gap_s = 0.5;
  double hum_hz = 0.0;             // noise sources: add a mains hum at this frequency
  // Alarms: 0 is the two-tone siren (960 / 770 Hz); > 0 a beeper (smoke alarm, reversing
  // alarm) at this frequency, on for the first half of every beep_period_s.
  double tone_hz = 0.0;
  double beep_period_s = 1.0;
};

// Shoebox acoustics for the image-source method: the room box, and either rt60_s (absorption
// set from it by Eyring's formula) or per-surface absorption (x-, x+, y-, y+, floor, ceiling).
struct Acoustics {
  bool reverb = true;
  Eigen::Vector3d room_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d room_max = Eigen::Vector3d::Zero();  // zero box: bounding box of the walls
  double rt60_s = 0.4;                                  // <= 0: use `absorption`
  std::vector<double> absorption;                       // 1 or 6 values in [0, 1]
  double ambient_noise_db_spl = 35.0;                   // diffuse background at the mics
};

struct RobotStart {
  Eigen::Vector3d pose{0, 0, 0};  // x, y, yaw
  std::vector<Eigen::Vector2d> path;  // scripted waypoints (map frame), may be empty
  double path_speed_mps = 0.3;
  double path_turn_radps = 0.6;
  bool path_loop = false;
};

struct World {
  std::string name;
  std::string source_file;
  bool lights_on = true;
  Rgb floor_colour{0.45f, 0.45f, 0.47f};
  Rgb ceiling_colour{0.9f, 0.9f, 0.9f};
  double ceiling_height_m = 0.0;  // 0: no ceiling (open area)
  std::vector<Wall> walls;        // including glass panels
  std::vector<Box> boxes;
  std::vector<Table> tables;
  std::vector<Person> people;
  std::vector<SoundSource> sources;
  Acoustics acoustics;
  RobotStart robot;

  // Room box used by the acoustics (explicit, or the walls' bounding box).
  void AcousticRoom(Eigen::Vector3d* room_min, Eigen::Vector3d* room_max) const;
  const Person* FindPerson(const std::string& name) const;
};

// Loads and checks a world file; throws WorldError("file:line:col: key: what").
World LoadWorld(const std::string& path);
// Same, from text (`name` stands for the file name in errors).
World ParseWorld(const std::string& yaml_text, const std::string& name);

// The world as a world file that ParseWorld reads back to the same world (numbers in their
// shortest exact decimal form, angles in whole degrees when that is exact, colours as the
// 0..255 values they came from); `header` (comment lines) goes first. Glass panels are listed
// after the walls, as the loader orders them.
std::string WorldToYaml(const World& world, const std::string& header = "");

const char* PostureName(Posture posture);
const char* SourceKindName(SourceKind kind);

}  // namespace sim
}  // namespace sarmap
