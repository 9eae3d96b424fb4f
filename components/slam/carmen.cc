#include "slam/carmen.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace slam {
namespace {

// Whitespace tokenizer with strict number parsing.
class Tokens {
 public:
  explicit Tokens(const std::string& line) {
    std::istringstream in(line);
    std::string t;
    while (in >> t) tokens_.push_back(t);
  }
  size_t size() const { return tokens_.size(); }
  size_t left() const { return tokens_.size() - pos_; }
  const std::string& Word() {
    if (pos_ >= tokens_.size()) throw std::runtime_error("line ends early");
    return tokens_[pos_++];
  }
  double Number() {
    const std::string& w = Word();
    char* end = nullptr;
    const double v = std::strtod(w.c_str(), &end);
    if (end == w.c_str() || *end != '\0') throw std::runtime_error("not a number: '" + w + "'");
    return v;
  }
  int Count(int max) {
    const double v = Number();
    if (v < 0 || v > max || v != std::floor(v)) throw std::runtime_error("bad count");
    return static_cast<int>(v);
  }

 private:
  std::vector<std::string> tokens_;
  size_t pos_ = 0;
};

constexpr int kMaxReadings = 100000;

}  // namespace

bool CarmenReader::ParseLine(const std::string& line, CarmenStats* stats) {
  ++stats->lines;
  size_t first = line.find_first_not_of(" \t\r");
  if (first == std::string::npos || line[first] == '#') {
    ++stats->skipped_comments;
    return true;
  }
  Tokens tok(line);
  const std::string type = tok.Word();
  try {
    if (type == "ODOM") {
      CarmenOdometry o;
      o.x_m = tok.Number();
      o.y_m = tok.Number();
      o.theta_rad = tok.Number();
      o.tv_mps = tok.Number();
      o.rv_radps = tok.Number();
      tok.Number();  // accel
      o.time_s = tok.Number();
      ++stats->odometry;
      if (on_odometry) on_odometry(o);
      return true;
    }
    if (type == "FLASER") {
      CarmenLaser l;
      l.source = type;
      const int n = tok.Count(kMaxReadings);
      if (n < 2) throw std::runtime_error("too few readings");
      l.ranges_m.resize(n);
      for (int i = 0; i < n; ++i) l.ranges_m[i] = static_cast<float>(tok.Number());
      tok.Number(), tok.Number(), tok.Number();  // laser pose (corrected), unused
      l.has_odometry = true;
      l.odometry.x_m = tok.Number();
      l.odometry.y_m = tok.Number();
      l.odometry.theta_rad = tok.Number();
      l.time_s = tok.Number();
      l.odometry.time_s = l.time_s;
      // Old front-laser lines: 180 deg from -90 deg, beams at both ends.
      l.angle_min_rad = -M_PI / 2;
      l.angle_increment_rad = M_PI / (n - 1);
      // SICK LMS "no return" is 81.91 m; anything at 80 m or beyond is treated as such.
      l.range_max_m = 80.0;
      ++stats->lasers;
      if (on_laser) on_laser(l);
      return true;
    }
    if (type == "RAWLASER1" || type == "ROBOTLASER1") {
      CarmenLaser l;
      l.source = type;
      tok.Number();  // laser type
      l.angle_min_rad = tok.Number();
      tok.Number();  // fov
      l.angle_increment_rad = tok.Number();
      l.range_max_m = tok.Number();
      tok.Number();  // accuracy
      tok.Number();  // remission mode
      const int n = tok.Count(kMaxReadings);
      l.ranges_m.resize(n);
      for (int i = 0; i < n; ++i) l.ranges_m[i] = static_cast<float>(tok.Number());
      const int nr = tok.Count(kMaxReadings);
      l.remissions.resize(nr);
      for (int i = 0; i < nr; ++i) l.remissions[i] = static_cast<float>(tok.Number());
      if (type == "ROBOTLASER1") {
        const double lx = tok.Number(), ly = tok.Number(), lt = tok.Number();
        const double rx = tok.Number(), ry = tok.Number(), rt = tok.Number();
        for (int i = 0; i < 5; ++i) tok.Number();  // tv rv safety distances turn axis
        l.has_odometry = true;
        l.odometry.x_m = rx;
        l.odometry.y_m = ry;
        l.odometry.theta_rad = rt;
        // base_from_laser = inverse(odom_from_base) * odom_from_laser
        const double c = std::cos(rt), s = std::sin(rt);
        l.base_from_laser_x_m = c * (lx - rx) + s * (ly - ry);
        l.base_from_laser_y_m = -s * (lx - rx) + c * (ly - ry);
        l.base_from_laser_yaw_rad = std::remainder(lt - rt, 2 * M_PI);
      }
      l.time_s = tok.Number();
      l.odometry.time_s = l.time_s;
      if (!(l.angle_increment_rad > 0) || !(l.range_max_m > 0)) {
        throw std::runtime_error("bad angular resolution or max range");
      }
      ++stats->lasers;
      if (on_laser) on_laser(l);
      return true;
    }
  } catch (const std::exception& e) {
    ++stats->malformed;
    if (warn && stats->malformed <= 5) {
      warn("line " + std::to_string(stats->lines) + " (" + type + "): " + e.what());
    }
    return false;
  }
  ++stats->skipped_unknown;
  return true;
}

CarmenStats CarmenReader::Read(std::istream& in) {
  CarmenStats stats;
  std::string line;
  int64_t bytes = 0, next_report = 1 << 20;
  while (std::getline(in, line)) {
    ParseLine(line, &stats);
    bytes += static_cast<int64_t>(line.size()) + 1;
    if (on_progress && bytes >= next_report) {
      on_progress(bytes);
      next_report += 1 << 20;
    }
  }
  return stats;
}

CarmenStats ReadCarmenFile(const std::string& path, CarmenReader* reader) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open CARMEN log '" + path + "'");
  return reader->Read(in);
}

CarmenLaser InterlacedLaser(const CarmenLaser& laser, int phase) {
  phase = ((phase % kInterlacePhases) + kInterlacePhases) % kInterlacePhases;
  const int first = phase == 0 || phase == 2 ? 0 : 1;
  const int step = phase < 2 ? 1 : 2;
  CarmenLaser out = laser;
  out.ranges_m.clear();
  out.remissions.clear();
  const int n = static_cast<int>(laser.ranges_m.size());
  const bool with_remissions = laser.remissions.size() == laser.ranges_m.size();
  for (int i = first; i < n; i += step) {
    out.ranges_m.push_back(laser.ranges_m[i]);
    if (with_remissions) out.remissions.push_back(laser.remissions[i]);
  }
  out.angle_min_rad = laser.angle_min_rad + first * laser.angle_increment_rad;
  out.angle_increment_rad = step * laser.angle_increment_rad;
  return out;
}

namespace {

void Append(std::string* line, const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  *line += buf;
}

}  // namespace

std::string FormatCarmenOdometry(const CarmenOdometry& o) {
  std::string line = "ODOM";
  for (double v : {o.x_m, o.y_m, o.theta_rad, o.tv_mps, o.rv_radps}) Append(&line, " %.6f", v);
  Append(&line, " %g", 0.0);  // acceleration
  Append(&line, " %.6f", o.time_s);
  line += " sarmap";
  Append(&line, " %.6f", o.time_s);
  return line;
}

std::string FormatCarmenLaser(const CarmenLaser& l) {
  const bool robot = l.source == "ROBOTLASER1";
  std::string line = robot ? "ROBOTLASER1 0" : "RAWLASER1 0";
  const int n = static_cast<int>(l.ranges_m.size());
  Append(&line, " %.9f", l.angle_min_rad);
  Append(&line, " %.9f", l.angle_increment_rad * std::max(0, n - 1));  // fov
  Append(&line, " %.9f", l.angle_increment_rad);
  Append(&line, " %g", l.range_max_m);
  line += " 0.01 0";  // accuracy, remission mode
  line += " " + std::to_string(n);
  for (float r : l.ranges_m) Append(&line, " %.9g", r);
  line += " " + std::to_string(l.remissions.size());
  for (float r : l.remissions) Append(&line, " %.9g", r);
  if (robot) {
    // odom_from_laser = odom_from_base * base_from_laser
    const CarmenOdometry& o = l.odometry;
    const double c = std::cos(o.theta_rad), s = std::sin(o.theta_rad);
    Append(&line, " %.6f", o.x_m + c * l.base_from_laser_x_m - s * l.base_from_laser_y_m);
    Append(&line, " %.6f", o.y_m + s * l.base_from_laser_x_m + c * l.base_from_laser_y_m);
    Append(&line, " %.6f", std::remainder(o.theta_rad + l.base_from_laser_yaw_rad, 2 * M_PI));
    for (double v : {o.x_m, o.y_m, o.theta_rad, o.tv_mps, o.rv_radps}) Append(&line, " %.6f", v);
    line += " 0 0 0";  // forward safety, side safety, turn axis
  }
  Append(&line, " %.6f", l.time_s);
  line += " sarmap";
  Append(&line, " %.6f", l.time_s);
  return line;
}

}  // namespace slam
}  // namespace sarmap
