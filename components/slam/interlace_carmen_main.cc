// sarmap-log-interlace-carmen: re-cuts a CARMEN log's laser lines into interlaced scans (each
// line with its own start angle, resolution and beam count, as an interlacing SICK scanner
// writes them), to test that everything using scans honours each scan's geometry.

#include <cstdio>
#include <fstream>
#include <string>

#include "common/args.h"
#include "common/logging.h"
#include "slam/carmen.h"

using namespace sarmap;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-interlace-carmen", [&]() -> int {
    std::string input, output;
    common::ArgParser args(
        "sarmap-log-interlace-carmen",
        "Writes a CARMEN log whose laser lines are interlaced: scan k keeps phase k % 4 of its "
        "sweep (all n beams; beams 1..n-1; even beams; odd beams), each a RAWLASER1 line with its "
        "own start angle, resolution and count (ROBOTLASER1 stays ROBOTLASER1). Odometry lines, "
        "and the odometry of FLASER lines, become ODOM lines; other lines are copied.");
    args.AddPositional("IN", &input, "CARMEN log (.log, .clf)");
    args.AddPositional("OUT", &output, "interlaced CARMEN log to write");
    if (!args.Parse(argc, argv)) return 0;

    std::ifstream in(input);
    if (!in) throw std::runtime_error("cannot open CARMEN log '" + input + "'");
    std::ofstream out(output);
    if (!out) throw std::runtime_error("cannot write '" + output + "'");
    out << "# Interlaced by sarmap-log-interlace-carmen from " << input
        << ": scan k is phase k % 4 of its sweep (all beams; beams 1..n-1; even; odd)\n";
    slam::CarmenReader reader;
    reader.warn = [](const std::string& w) { SARMAP_LOG(WARN) << "skipping malformed " << w; };
    int64_t scans = 0, odometry = 0, copied = 0;
    bool line_used = false;
    reader.on_odometry = [&](const slam::CarmenOdometry& o) {
      out << slam::FormatCarmenOdometry(o) << "\n";
      ++odometry;
      line_used = true;
    };
    reader.on_laser = [&](const slam::CarmenLaser& l) {
      if (l.source == "FLASER") {
        out << slam::FormatCarmenOdometry(l.odometry) << "\n";
        ++odometry;
      }
      out << slam::FormatCarmenLaser(slam::InterlacedLaser(l, static_cast<int>(scans++))) << "\n";
      line_used = true;
    };
    slam::CarmenStats stats;
    std::string line;
    while (std::getline(in, line)) {
      line_used = false;
      if (!reader.ParseLine(line, &stats)) continue;  // malformed: counted, dropped
      if (!line_used) {
        out << line << "\n";  // comments and other message types
        ++copied;
      }
    }
    if (!out.flush()) throw std::runtime_error("write failed: '" + output + "'");
    std::printf(
        "%s -> %s: %lld scans interlaced, %lld odometry lines, %lld other lines copied, "
        "%lld malformed lines dropped\n",
        input.c_str(), output.c_str(), (long long)scans, (long long)odometry, (long long)copied,
        (long long)stats.malformed);
    return 0;
  });
}
