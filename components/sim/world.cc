#include "sim/world.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace sarmap {
namespace sim {
namespace {

std::string Loc(const std::string& file, const YAML::Mark& mark) {
  if (mark.is_null()) return file;
  return file + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

// Reads one YAML mapping, remembers which keys were used, and reports every problem as
// "file:line:col: key.path: what".
class MapReader {
 public:
  MapReader(const YAML::Node& node, const std::string& file, const std::string& path)
      : node_(node), file_(file), path_(path) {
    if (!node_.IsMap()) Fail(node_, "", "expected a mapping");
  }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& key,
                         const std::string& what) const {
    const std::string full = path_.empty() ? key : (key.empty() ? path_ : path_ + "." + key);
    throw WorldError(Loc(file_, at.Mark()) + ": " + (full.empty() ? "" : full + ": ") + what);
  }
  [[noreturn]] void FailKey(const std::string& key, const std::string& what) const {
    Fail(Has(key) ? node_[key] : node_, key, what);
  }

  bool Has(const std::string& key) const { return static_cast<bool>(node_[key]); }
  YAML::Node Get(const std::string& key) {
    used_.insert(key);
    return node_[key];
  }
  std::string Path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& file() const { return file_; }

  double Double(const std::string& key, double fallback) {
    if (!Has(key)) return fallback;
    const YAML::Node n = Get(key);
    return ScalarDouble(n, key);
  }
  double Required(const std::string& key) {
    if (!Has(key)) Fail(node_, key, "required key missing");
    return Double(key, 0.0);
  }
  double Positive(const std::string& key, double fallback) {
    const double v = Double(key, fallback);
    if (!(v > 0)) FailKey(key, "must be > 0");
    return v;
  }
  double NonNegative(const std::string& key, double fallback) {
    const double v = Double(key, fallback);
    if (!(v >= 0)) FailKey(key, "must be >= 0");
    return v;
  }
  bool Bool(const std::string& key, bool fallback) {
    if (!Has(key)) return fallback;
    const YAML::Node n = Get(key);
    try {
      if (n.IsScalar()) return n.as<bool>();
    } catch (const YAML::Exception&) {
    }
    Fail(n, key, "expected true or false");
  }
  std::string String(const std::string& key, const std::string& fallback) {
    if (!Has(key)) return fallback;
    const YAML::Node n = Get(key);
    if (!n.IsScalar()) Fail(n, key, "expected a string");
    return n.Scalar();
  }
  std::vector<double> Doubles(const std::string& key, size_t min_size, size_t max_size) {
    const YAML::Node n = Get(key);
    if (!n.IsSequence()) Fail(n, key, "expected a list of numbers");
    if (n.size() < min_size || n.size() > max_size) {
      Fail(n, key, min_size == max_size
                       ? "expected " + std::to_string(min_size) + " numbers, got " +
                             std::to_string(n.size())
                       : "expected " + std::to_string(min_size) + " to " +
                             std::to_string(max_size) + " numbers, got " + std::to_string(n.size()));
    }
    std::vector<double> out;
    for (size_t i = 0; i < n.size(); ++i) out.push_back(ScalarDouble(n[i], key + "[" + std::to_string(i) + "]"));
    return out;
  }
  Eigen::Vector2d Vec2(const std::string& key) {
    if (!Has(key)) Fail(node_, key, "required key missing");
    auto v = Doubles(key, 2, 2);
    return {v[0], v[1]};
  }
  Eigen::Vector3d Vec3(const std::string& key) {
    if (!Has(key)) Fail(node_, key, "required key missing");
    auto v = Doubles(key, 3, 3);
    return {v[0], v[1], v[2]};
  }
  Rgb Colour(const std::string& key, Rgb fallback) {
    if (!Has(key)) return fallback;
    auto v = Doubles(key, 3, 3);
    for (double c : v) {
      if (c < 0 || c > 255) FailKey(key, "colour components are 0..255");
    }
    return Rgb{static_cast<float>(v[0] / 255), static_cast<float>(v[1] / 255),
               static_cast<float>(v[2] / 255)};
  }
  double Angle(const std::string& key) {  // yaw_deg or yaw_rad
    if (Has(key + "_deg")) return Double(key + "_deg", 0) * M_PI / 180.0;
    return Double(key + "_rad", 0);
  }

  // Every key not read is a typo or a misplaced key: an error, not a silent default.
  void Finish() const {
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      const std::string key = it->first.Scalar();
      if (!used_.count(key)) {
        throw WorldError(Loc(file_, it->first.Mark()) + ": " + Path(key) + ": unknown key");
      }
    }
  }

 private:
  double ScalarDouble(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) Fail(n, key, "expected a number");
    try {
      const double v = n.as<double>();
      if (std::isfinite(v)) return v;
    } catch (const YAML::Exception&) {
    }
    Fail(n, key, "expected a number, got '" + n.Scalar() + "'");
  }

  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

// Iterates a list-valued key, handing each element's reader to `each`.
template <class F>
void ForEach(MapReader& parent, const std::string& key, F each) {
  if (!parent.Has(key)) return;
  const YAML::Node list = parent.Get(key);
  if (!list.IsSequence()) parent.Fail(list, key, "expected a list");
  for (size_t i = 0; i < list.size(); ++i) {
    MapReader item(list[i], parent.file(), parent.Path(key) + "[" + std::to_string(i) + "]");
    each(item);
    item.Finish();
  }
}

Wall ReadWall(MapReader& r, bool glass) {
  Wall w;
  w.glass = glass;
  w.name = r.String("name", glass ? "glass" : "wall");
  w.from = r.Vec2("from");
  w.to = r.Vec2("to");
  if ((w.to - w.from).norm() < 1e-3) r.FailKey("to", "wall has zero length");
  w.height_m = r.Positive("height_m", glass ? 2.2 : 2.5);
  w.thickness_m = r.Positive("thickness_m", glass ? 0.02 : 0.1);
  w.base_m = r.NonNegative("base_m", 0.0);
  w.colour = r.Colour("colour", glass ? Rgb{0.75f, 0.85f, 0.9f} : w.colour);
  return w;
}

}  // namespace

Eigen::Vector3d Person::Mouth() const {
  switch (posture) {
    case Posture::kSitting:
      return {position.x(), position.y(), 0.70 * height_m};
    case Posture::kLying:
      return {position.x() + 0.75 * std::cos(yaw_rad), position.y() + 0.75 * std::sin(yaw_rad), 0.2};
    case Posture::kStanding:
    default:
      return {position.x(), position.y(), 0.92 * height_m};
  }
}

const char* PostureName(Posture posture) {
  switch (posture) {
    case Posture::kSitting: return "sitting";
    case Posture::kLying: return "lying";
    default: return "standing";
  }
}

const char* SourceKindName(SourceKind kind) {
  switch (kind) {
    case SourceKind::kMusic: return "music";
    case SourceKind::kAlarm: return "alarm";
    case SourceKind::kNoise: return "noise";
    default: return "voice";
  }
}

void World::AcousticRoom(Eigen::Vector3d* room_min, Eigen::Vector3d* room_max) const {
  if ((acoustics.room_max - acoustics.room_min).minCoeff() > 0) {
    *room_min = acoustics.room_min;
    *room_max = acoustics.room_max;
    return;
  }
  Eigen::Vector3d lo(1e9, 1e9, 0), hi(-1e9, -1e9, ceiling_height_m > 0 ? ceiling_height_m : 3.0);
  for (const Wall& w : walls) {
    for (const auto& p : {w.from, w.to}) {
      lo.head<2>() = lo.head<2>().cwiseMin(p);
      hi.head<2>() = hi.head<2>().cwiseMax(p);
    }
    if (ceiling_height_m <= 0) hi.z() = std::max(hi.z(), w.height_m);
  }
  if (walls.empty()) {
    lo << -10, -10, 0;
    hi << 10, 10, 3;
  }
  *room_min = lo;
  *room_max = hi;
}

const Person* World::FindPerson(const std::string& person_name) const {
  for (const Person& p : people) {
    if (p.name == person_name) return &p;
  }
  return nullptr;
}

World ParseWorld(const std::string& yaml_text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw WorldError(Loc(name, e.mark) + ": YAML syntax error: " + e.msg);
  }
  if (!root.IsMap()) throw WorldError(name + ": a world file is a YAML mapping");
  MapReader r(root, name, "");
  World world;
  world.source_file = name;
  world.name = r.String("name", "world");
  world.lights_on = r.Bool("lights_on", true);
  world.floor_colour = r.Colour("floor_colour", world.floor_colour);
  world.ceiling_colour = r.Colour("ceiling_colour", world.ceiling_colour);
  world.ceiling_height_m = r.NonNegative("ceiling_height_m", 0.0);

  ForEach(r, "walls", [&](MapReader& w) { world.walls.push_back(ReadWall(w, false)); });
  ForEach(r, "glass", [&](MapReader& w) { world.walls.push_back(ReadWall(w, true)); });
  ForEach(r, "boxes", [&](MapReader& b) {
    Box box;
    box.name = b.String("name", "box");
    box.centre = b.Vec2("centre");
    box.yaw_rad = b.Angle("yaw");
    const Eigen::Vector3d size = b.Vec3("size_m");
    if (size.minCoeff() <= 0) b.FailKey("size_m", "sizes must be > 0");
    box.size_m = size;
    box.base_m = b.NonNegative("base_m", 0.0);
    box.colour = b.Colour("colour", box.colour);
    world.boxes.push_back(box);
  });
  ForEach(r, "tables", [&](MapReader& t) {
    Table table;
    table.name = t.String("name", "table");
    table.centre = t.Vec2("centre");
    table.yaw_rad = t.Angle("yaw");
    table.size_m = t.Vec2("size_m");
    if (table.size_m.minCoeff() <= 0) t.FailKey("size_m", "sizes must be > 0");
    table.height_m = t.Positive("height_m", table.height_m);
    table.top_thickness_m = t.Positive("top_thickness_m", table.top_thickness_m);
    table.leg_width_m = t.Positive("leg_width_m", table.leg_width_m);
    if (table.top_thickness_m >= table.height_m) t.FailKey("top_thickness_m", "must be < height_m");
    table.colour = t.Colour("colour", table.colour);
    world.tables.push_back(table);
  });
  std::set<std::string> names;
  ForEach(r, "people", [&](MapReader& p) {
    Person person;
    person.id = static_cast<int>(world.people.size()) + 1;
    person.name = p.String("name", "person" + std::to_string(person.id));
    if (!names.insert(person.name).second) p.FailKey("name", "duplicate person name '" + person.name + "'");
    person.position = p.Vec2("position");
    person.yaw_rad = p.Angle("yaw");
    const std::string posture = p.String("posture", "standing");
    if (posture == "standing") person.posture = Posture::kStanding;
    else if (posture == "sitting") person.posture = Posture::kSitting;
    else if (posture == "lying") person.posture = Posture::kLying;
    else p.FailKey("posture", "must be standing, sitting or lying, is '" + posture + "'");
    person.height_m = p.Positive("height_m", 1.75);
    if (person.height_m < 0.5 || person.height_m > 2.5) p.FailKey("height_m", "must be in [0.5, 2.5]");
    person.appearance = static_cast<int>(p.Double("appearance", -1));
    world.people.push_back(person);
  });
  ForEach(r, "sources", [&](MapReader& s) {
    SoundSource src;
    src.id = static_cast<int>(world.sources.size()) + 1;
    src.name = s.String("name", "source" + std::to_string(src.id));
    const std::string kind = s.String("kind", "voice");
    if (kind == "voice") src.kind = SourceKind::kVoice;
    else if (kind == "music") src.kind = SourceKind::kMusic;
    else if (kind == "alarm") src.kind = SourceKind::kAlarm;
    else if (kind == "noise") src.kind = SourceKind::kNoise;
    else s.FailKey("kind", "must be voice, music, alarm or noise, is '" + kind + "'");
    if (s.Has("person")) {
      const std::string who = s.String("person", "");
      const Person* person = world.FindPerson(who);
      if (!person) s.FailKey("person", "no person named '" + who + "' (list people before sources)");
      src.person_id = person->id;
      src.position = person->Mouth();
      if (s.Has("position")) s.FailKey("position", "give either person or position, not both");
    } else {
      src.position = s.Vec3("position");
    }
    const double default_db = src.kind == SourceKind::kVoice   ? 65.0
                              : src.kind == SourceKind::kAlarm ? 75.0
                              : src.kind == SourceKind::kMusic ? 60.0
                                                               : 50.0;
    src.level_db_spl = s.Double("level_db_spl", default_db);
    if (src.level_db_spl < 0 || src.level_db_spl > 120) s.FailKey("level_db_spl", "must be in [0, 120]");
    if (s.Has("clips")) {
      const YAML::Node clips = s.Get("clips");
      if (!clips.IsSequence() || clips.size() == 0) s.Fail(clips, "clips", "expected a non-empty list");
      for (size_t i = 0; i < clips.size(); ++i) {
        if (!clips[i].IsScalar()) s.Fail(clips[i], "clips", "expected strings");
        src.clips.push_back(clips[i].Scalar());
      }
    }
    if (src.kind == SourceKind::kVoice && src.clips.empty()) s.FailKey("clips", "a voice needs clips");
    if (src.kind != SourceKind::kVoice && !src.clips.empty()) s.FailKey("clips", "only voices have clips");
    src.start_s = s.NonNegative("start_s", 0.0);
    src.every_s = s.NonNegative("every_s", 0.0);
    src.duration_s = s.NonNegative("duration_s", 0.0);
    src.stop_s = s.Has("stop_s") ? s.Positive("stop_s", 1.0) : src.stop_s;
    src.continuous = s.Bool("continuous", false);
    src.gap_s = s.NonNegative("gap_s", 0.5);
    src.hum_hz = s.NonNegative("hum_hz", 0.0);
    src.tone_hz = s.NonNegative("tone_hz", 0.0);
    src.beep_period_s = s.Has("beep_period_s") ? s.Positive("beep_period_s", 1.0) : 1.0;
    if (src.tone_hz > 0 && src.kind != SourceKind::kAlarm)
      s.FailKey("tone_hz", "only alarms have tone_hz");
    if (src.tone_hz >= 8000)
      s.FailKey("tone_hz", "must be below 8000 Hz (half the 16 kHz audio rate)");
    if (src.continuous && src.every_s > 0) s.FailKey("every_s", "a continuous source has no every_s");
    world.sources.push_back(src);
  });
  if (r.Has("acoustics")) {
    MapReader a(r.Get("acoustics"), name, "acoustics");
    world.acoustics.reverb = a.Bool("reverb", true);
    if (a.Has("room_min") || a.Has("room_max")) {
      world.acoustics.room_min = a.Vec3("room_min");
      world.acoustics.room_max = a.Vec3("room_max");
      if ((world.acoustics.room_max - world.acoustics.room_min).minCoeff() <= 0) {
        a.FailKey("room_max", "must exceed room_min in x, y and z");
      }
    }
    world.acoustics.rt60_s = a.Double("rt60_s", world.acoustics.rt60_s);
    if (world.acoustics.rt60_s > 3.0) a.FailKey("rt60_s", "must be <= 3 s");
    if (a.Has("absorption")) {
      world.acoustics.absorption = a.Doubles("absorption", 1, 6);
      if (world.acoustics.absorption.size() != 1 && world.acoustics.absorption.size() != 6) {
        a.FailKey("absorption", "give 1 value or 6 (x-, x+, y-, y+, floor, ceiling)");
      }
      for (double v : world.acoustics.absorption) {
        if (v < 0 || v > 1) a.FailKey("absorption", "values must be in [0, 1]");
      }
      if (!a.Has("rt60_s")) world.acoustics.rt60_s = 0;
    }
    if (world.acoustics.reverb && world.acoustics.rt60_s <= 0 && world.acoustics.absorption.empty()) {
      a.FailKey("rt60_s", "reverb needs rt60_s > 0 or absorption");
    }
    world.acoustics.ambient_noise_db_spl = a.Double("ambient_noise_db_spl", 35.0);
    a.Finish();
  }
  if (r.Has("robot")) {
    MapReader rb(r.Get("robot"), name, "robot");
    if (rb.Has("start")) world.robot.pose = rb.Vec3("start");
    if (rb.Has("start_yaw_deg")) rb.FailKey("start_yaw_deg", "give the yaw as the third value of start (radians)");
    if (rb.Has("path")) {
      const YAML::Node path = rb.Get("path");
      if (!path.IsSequence()) rb.Fail(path, "path", "expected a list of [x, y]");
      for (size_t i = 0; i < path.size(); ++i) {
        if (!path[i].IsSequence() || path[i].size() != 2) {
          rb.Fail(path[i], "path[" + std::to_string(i) + "]", "expected [x, y]");
        }
        try {
          world.robot.path.emplace_back(path[i][0].as<double>(), path[i][1].as<double>());
        } catch (const YAML::Exception&) {
          rb.Fail(path[i], "path[" + std::to_string(i) + "]", "expected numbers");
        }
      }
    }
    world.robot.path_speed_mps = rb.Positive("path_speed_mps", world.robot.path_speed_mps);
    world.robot.path_turn_radps = rb.Positive("path_turn_radps", world.robot.path_turn_radps);
    world.robot.path_loop = rb.Bool("path_loop", false);
    rb.Finish();
  }
  r.Finish();
  return world;
}

World LoadWorld(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw WorldError(path + ": cannot open world file");
  std::stringstream text;
  text << in.rdbuf();
  return ParseWorld(text.str(), path);
}

}  // namespace sim
}  // namespace sarmap
