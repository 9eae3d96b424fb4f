// sarmap-log-interlace-carmen: re-cuts a CARMEN log's laser lines into interlaced scans (each
// line with its own start angle, resolution and beam count, as an interlacing SICK scanner
// writes them), to test that everything using scans honours each scan's geometry. With
// --laps N the log is driven N times in a row (a longer mission over the same site).

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/logging.h"
#include "common/transform.h"
#include "slam/carmen.h"

using namespace sarmap;

namespace {

common::Rigid2d Pose(const slam::CarmenOdometry& o) {
  return common::Rigid2d(o.x_m, o.y_m, o.theta_rad);
}

void SetPose(const common::Rigid2d& p, slam::CarmenOdometry* o) {
  o->x_m = p.translation().x();
  o->y_m = p.translation().y();
  o->theta_rad = p.yaw_rad();
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-interlace-carmen", [&]() -> int {
    std::string input, output, relations, relations_output;
    int laps = 1;
    common::ArgParser args(
        "sarmap-log-interlace-carmen",
        "Writes a CARMEN log whose laser lines are interlaced: scan k keeps phase k % 4 of its "
        "sweep (all n beams; beams 1..n-1; even beams; odd beams), each a RAWLASER1 line with its "
        "own start angle, resolution and count (ROBOTLASER1 stays ROBOTLASER1). Odometry lines, "
        "and the odometry of FLASER lines, become ODOM lines; other lines are copied.");
    args.AddPositional("IN", &input, "CARMEN log (.log, .clf)");
    args.AddPositional("OUT", &output, "interlaced CARMEN log to write");
    args.AddFlag("--laps", &laps,
                 "drive the log this many times in a row: each lap's stamps follow the previous "
                 "lap's (1 s after its latest stamp) and its odometry continues where the previous "
                 "lap's ended (for a log that ends near its start)");
    args.AddFlag("--relations", &relations, "a .relations file of IN, repeated for every lap");
    args.AddFlag("--relations-output", &relations_output, "where to write them");
    if (!args.Parse(argc, argv)) return 0;
    if (laps < 1 || laps > 100) throw common::ArgError("--laps must be 1..100");
    if (relations.empty() != relations_output.empty()) {
      throw common::ArgError("--relations and --relations-output go together");
    }

    std::ifstream in(input);
    if (!in) throw std::runtime_error("cannot open CARMEN log '" + input + "'");
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);

    // The lap's span of stamps and its first and last odometry.
    double min_t = 1e300, max_t = -1e300;
    bool have_odometry = false;
    common::Rigid2d first_odometry, last_odometry;
    {
      slam::CarmenReader scan;
      const auto odometry = [&](const slam::CarmenOdometry& o) {
        min_t = std::min(min_t, o.time_s);
        max_t = std::max(max_t, o.time_s);
        if (!have_odometry) first_odometry = Pose(o);
        have_odometry = true;
        last_odometry = Pose(o);
      };
      scan.on_odometry = odometry;
      scan.on_laser = [&](const slam::CarmenLaser& l) {
        min_t = std::min(min_t, l.time_s);
        max_t = std::max(max_t, l.time_s);
        if (l.has_odometry) odometry(l.odometry);
      };
      slam::CarmenStats stats;
      for (const std::string& line : lines) scan.ParseLine(line, &stats);
      if (stats.lasers == 0) throw std::runtime_error("no laser lines in '" + input + "'");
    }
    const double lap_s = max_t - min_t + 1.0;
    // Lap k's odometry: odom_from_lap_k * the log's odometry, so that lap k starts where lap
    // k - 1 ended.
    const common::Rigid2d lap_step = last_odometry * first_odometry.inverse();

    std::ofstream out(output);
    if (!out) throw std::runtime_error("cannot write '" + output + "'");
    out << "# Interlaced by sarmap-log-interlace-carmen from " << input
        << ": scan k is phase k % 4 of its sweep (all beams; beams 1..n-1; even; odd)";
    if (laps > 1) out << ", " << laps << " laps of " << lap_s << " s";
    out << "\n";
    slam::CarmenReader reader;
    reader.warn = [](const std::string& w) { SARMAP_LOG(WARN) << "skipping malformed " << w; };
    int64_t scans = 0, odometry = 0, copied = 0;
    bool line_used = false;
    common::Rigid2d odom_from_lap;
    double shift_s = 0;
    const auto moved = [&](slam::CarmenOdometry o) {
      o.time_s += shift_s;
      SetPose(odom_from_lap * Pose(o), &o);
      return o;
    };
    reader.on_odometry = [&](const slam::CarmenOdometry& o) {
      out << slam::FormatCarmenOdometry(moved(o)) << "\n";
      ++odometry;
      line_used = true;
    };
    reader.on_laser = [&](const slam::CarmenLaser& l) {
      slam::CarmenLaser cut = slam::InterlacedLaser(l, static_cast<int>(scans++));
      cut.time_s += shift_s;
      if (l.has_odometry) cut.odometry = moved(l.odometry);
      if (l.source == "FLASER") {
        out << slam::FormatCarmenOdometry(cut.odometry) << "\n";
        ++odometry;
      }
      out << slam::FormatCarmenLaser(cut) << "\n";
      line_used = true;
    };
    slam::CarmenStats stats;
    for (int lap = 0; lap < laps; ++lap) {
      shift_s = lap * lap_s;
      for (const std::string& line : lines) {
        line_used = false;
        if (!reader.ParseLine(line, &stats)) continue;  // malformed: counted, dropped
        if (!line_used && lap == 0) {
          out << line << "\n";  // comments and other message types, once
          ++copied;
        }
      }
      odom_from_lap = odom_from_lap * lap_step;
    }
    if (!out.flush()) throw std::runtime_error("write failed: '" + output + "'");
    std::printf(
        "%s -> %s: %lld scans interlaced, %lld odometry lines, %lld other lines copied, "
        "%lld malformed lines dropped",
        input.c_str(), output.c_str(), (long long)scans, (long long)odometry, (long long)copied,
        (long long)stats.malformed);
    if (laps > 1) std::printf(", %d laps of %.1f s", laps, lap_s);
    std::printf("\n");

    if (!relations.empty()) {
      std::ifstream rin(relations);
      if (!rin) throw std::runtime_error("cannot open relations '" + relations + "'");
      std::vector<std::string> rlines;
      for (std::string line; std::getline(rin, line);) rlines.push_back(line);
      std::ofstream rout(relations_output);
      if (!rout) throw std::runtime_error("cannot write '" + relations_output + "'");
      int64_t written = 0;
      for (int lap = 0; lap < laps; ++lap) {
        for (const std::string& line : rlines) {
          std::istringstream fields(line);
          double t1 = 0, t2 = 0;
          if (!(fields >> t1 >> t2)) continue;  // comments, blank lines
          std::string rest;
          std::getline(fields, rest);
          char stamps[64];
          std::snprintf(stamps, sizeof(stamps), "%.6f %.6f", t1 + lap * lap_s, t2 + lap * lap_s);
          rout << stamps << rest << "\n";
          ++written;
        }
      }
      if (!rout.flush()) throw std::runtime_error("write failed: '" + relations_output + "'");
      std::printf("%s -> %s: %lld relations\n", relations.c_str(), relations_output.c_str(),
                  (long long)written);
    }
    return 0;
  });
}
