// WorldToYaml: a world back to the file format of WORLD_FORMAT.md.
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "sim/world.h"

namespace sarmap {
namespace sim {
namespace {

// The shortest decimal for `v` that `reads_back` accepts, in plain notation (90, not 9e+01)
// unless the magnitude needs an exponent.
template <typename ReadsBack>
std::string Shortest(double v, ReadsBack reads_back) {
  char buf[64];
  const bool plain = std::abs(v) >= 1e-4 && std::abs(v) < 1e15;
  for (int p = 0; p <= 17; ++p) {
    if (plain) {
      std::snprintf(buf, sizeof buf, "%.*f", p, v);
    } else {
      std::snprintf(buf, sizeof buf, "%.*g", std::max(p, 1), v);
    }
    if (reads_back(std::strtod(buf, nullptr))) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The shortest decimal that reads back as exactly `v`.
std::string Num(double v) {
  if (v == 0) return "0";
  return Shortest(v, [v](double r) { return r == v; });
}

std::string Vec(std::initializer_list<double> v) {
  std::string out = "[";
  for (double x : v) out += (out.size() > 1 ? ", " : "") + Num(x);
  return out + "]";
}

// Plain YAML scalars stay bare; anything YAML could read as another type or as syntax is
// double-quoted.
std::string Str(const std::string& s) {
  bool plain = !s.empty() && (std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_');
  for (char c : s) {
    plain = plain && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ||
                      c == '.' || c == '/');
  }
  for (const char* word : {"true", "false", "yes", "no", "on", "off", "null", "y", "n"}) {
    std::string lower;
    for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    plain = plain && lower != word;
  }
  if (plain) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// A colour component as the 0..255 value the loader turns back into it: float(v / 255).
std::string Component(float c) {
  return Shortest(static_cast<double>(c) * 255, [c](double r) { return static_cast<float>(r / 255) == c; });
}

std::string Colour(const Rgb& c) {
  return "[" + Component(c.r) + ", " + Component(c.g) + ", " + Component(c.b) + "]";
}

// ", yaw_deg: D" when D reads back to exactly `yaw_rad`, else ", yaw_rad: R"; nothing for 0.
std::string Yaw(double yaw_rad) {
  if (yaw_rad == 0) return "";
  const std::string deg =
      Shortest(yaw_rad * 180.0 / M_PI, [yaw_rad](double r) { return r * M_PI / 180.0 == yaw_rad; });
  if (std::strtod(deg.c_str(), nullptr) * M_PI / 180.0 == yaw_rad && deg.size() <= 14) return ", yaw_deg: " + deg;
  return ", yaw_rad: " + Num(yaw_rad);
}

void WriteWall(std::ostream& out, const Wall& w) {
  out << "  - {name: " << Str(w.name) << ", from: " << Vec({w.from.x(), w.from.y()})
      << ", to: " << Vec({w.to.x(), w.to.y()}) << ", height_m: " << Num(w.height_m)
      << ", thickness_m: " << Num(w.thickness_m);
  if (w.base_m != 0) out << ", base_m: " << Num(w.base_m);
  out << ", colour: " << Colour(w.colour) << "}\n";
}

}  // namespace

std::string WorldToYaml(const World& world, const std::string& header) {
  std::ostringstream out;
  out << header;
  out << "name: " << Str(world.name) << "\n"
      << "lights_on: " << (world.lights_on ? "true" : "false") << "\n"
      << "ceiling_height_m: " << Num(world.ceiling_height_m) << "\n"
      << "floor_colour: " << Colour(world.floor_colour) << "\n"
      << "ceiling_colour: " << Colour(world.ceiling_colour) << "\n";
  for (bool glass : {false, true}) {
    bool any = false;
    for (const Wall& w : world.walls) any = any || w.glass == glass;
    if (!any) continue;
    out << (glass ? "glass:\n" : "walls:\n");
    for (const Wall& w : world.walls) {
      if (w.glass == glass) WriteWall(out, w);
    }
  }
  if (!world.boxes.empty()) out << "boxes:\n";
  for (const Box& b : world.boxes) {
    out << "  - {name: " << Str(b.name) << ", centre: " << Vec({b.centre.x(), b.centre.y()})
        << Yaw(b.yaw_rad) << ", size_m: " << Vec({b.size_m.x(), b.size_m.y(), b.size_m.z()});
    if (b.base_m != 0) out << ", base_m: " << Num(b.base_m);
    out << ", colour: " << Colour(b.colour) << "}\n";
  }
  if (!world.tables.empty()) out << "tables:\n";
  for (const Table& t : world.tables) {
    out << "  - {name: " << Str(t.name) << ", centre: " << Vec({t.centre.x(), t.centre.y()})
        << Yaw(t.yaw_rad) << ", size_m: " << Vec({t.size_m.x(), t.size_m.y()})
        << ", height_m: " << Num(t.height_m) << ", top_thickness_m: " << Num(t.top_thickness_m)
        << ", leg_width_m: " << Num(t.leg_width_m) << ", colour: " << Colour(t.colour) << "}\n";
  }
  if (!world.people.empty()) out << "people:\n";
  for (const Person& p : world.people) {
    out << "  - {name: " << Str(p.name) << ", position: " << Vec({p.position.x(), p.position.y()})
        << Yaw(p.yaw_rad) << ", posture: " << PostureName(p.posture)
        << ", height_m: " << Num(p.height_m);
    if (p.appearance != -1) out << ", appearance: " << p.appearance;
    out << "}\n";
  }
  if (!world.sources.empty()) out << "sources:\n";
  for (const SoundSource& s : world.sources) {
    out << "  - {name: " << Str(s.name) << ", kind: " << SourceKindName(s.kind);
    const Person* person = nullptr;
    for (const Person& p : world.people) {
      if (p.id == s.person_id) person = &p;
    }
    if (person) {
      out << ", person: " << Str(person->name);
    } else {
      out << ", position: " << Vec({s.position.x(), s.position.y(), s.position.z()});
    }
    out << ", level_db_spl: " << Num(s.level_db_spl);
    if (!s.clips.empty()) {
      out << ", clips: [";
      for (size_t i = 0; i < s.clips.size(); ++i) out << (i ? ", " : "") << Str(s.clips[i]);
      out << "]";
    }
    if (s.start_s != 0) out << ", start_s: " << Num(s.start_s);
    if (s.every_s != 0) out << ", every_s: " << Num(s.every_s);
    if (s.duration_s != 0) out << ", duration_s: " << Num(s.duration_s);
    if (std::isfinite(s.stop_s)) out << ", stop_s: " << Num(s.stop_s);
    if (s.continuous) out << ", continuous: true";
    if (s.gap_s != 0.5) out << ", gap_s: " << Num(s.gap_s);
    if (s.hum_hz != 0) out << ", hum_hz: " << Num(s.hum_hz);
    if (s.tone_hz != 0) out << ", tone_hz: " << Num(s.tone_hz);
    if (s.beep_period_s != 1.0) out << ", beep_period_s: " << Num(s.beep_period_s);
    out << "}\n";
  }
  const Acoustics& a = world.acoustics;
  out << "acoustics:\n  reverb: " << (a.reverb ? "true" : "false") << "\n";
  if ((a.room_max - a.room_min).minCoeff() > 0) {
    out << "  room_min: " << Vec({a.room_min.x(), a.room_min.y(), a.room_min.z()}) << "\n"
        << "  room_max: " << Vec({a.room_max.x(), a.room_max.y(), a.room_max.z()}) << "\n";
  }
  if (a.absorption.empty() || a.rt60_s > 0) out << "  rt60_s: " << Num(a.rt60_s) << "\n";
  if (!a.absorption.empty()) {
    out << "  absorption: [";
    for (size_t i = 0; i < a.absorption.size(); ++i) out << (i ? ", " : "") << Num(a.absorption[i]);
    out << "]\n";
  }
  out << "  ambient_noise_db_spl: " << Num(a.ambient_noise_db_spl) << "\n";
  const RobotStart& r = world.robot;
  out << "robot:\n  start: " << Vec({r.pose.x(), r.pose.y(), r.pose.z()}) << "\n";
  if (!r.path.empty()) {
    out << "  path: [";
    for (size_t i = 0; i < r.path.size(); ++i)
      out << (i ? ", " : "") << Vec({r.path[i].x(), r.path[i].y()});
    out << "]\n";
  }
  out << "  path_speed_mps: " << Num(r.path_speed_mps) << "\n"
      << "  path_turn_radps: " << Num(r.path_turn_radps) << "\n"
      << "  path_loop: " << (r.path_loop ? "true" : "false") << "\n";
  return out.str();
}

}  // namespace sim
}  // namespace sarmap
