// sarmap-log-import-carmen: CARMEN text log (ODOM, FLASER, RAWLASER1, ROBOTLASER1) -> LCM log
// of ODOM (odometry_t) and SCAN (laser_scan_t) events with the original timestamps.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <vector>

#include "common/args.h"
#include "common/logging.h"
#include "common/time.h"
#include "log-tools/lcm_log_writer.h"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "slam/carmen.h"
#include "slam/carmen_messages.h"

using namespace sarmap;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-import-carmen", [&]() -> int {
    std::string input, output, odom_channel = "ODOM", scan_channel = "SCAN";
    common::ArgParser args("sarmap-log-import-carmen",
                           "Converts a CARMEN log (ODOM, FLASER, RAWLASER1, ROBOTLASER1) into an "
                           "LCM log of odometry_t and laser_scan_t with the original timestamps.");
    args.AddPositional("CARMEN_LOG", &input, "input CARMEN text log (.log, .clf)");
    args.AddPositional("LCM_LOG", &output, "output LCM log file");
    args.AddFlag("--odom-channel", &odom_channel, "channel for odometry");
    args.AddFlag("--scan-channel", &scan_channel, "channel for laser scans");
    if (!args.Parse(argc, argv)) return 0;

    logtools::LcmLogWriter log(output);
    int64_t odom_seq = 0, scan_seq = 0, laser_offsets = 0;
    auto write = [&](const std::string& channel, auto& msg) {
      log.Write(channel, msg, msg.header.utime);
    };
    slam::CarmenReader reader;
    reader.warn = [](const std::string& w) { SARMAP_LOG(WARN) << "skipping malformed " << w; };
    reader.on_odometry = [&](const slam::CarmenOdometry& o) {
      odometry_t msg = slam::ToOdometryMessage(o);
      msg.header.seq = odom_seq++;
      write(odom_channel, msg);
    };
    reader.on_laser = [&](const slam::CarmenLaser& l) {
      if (l.has_odometry) {  // FLASER / ROBOTLASER1 carry the odometry at the scan time
        odometry_t msg = slam::ToOdometryMessage(l.odometry);
        msg.header.seq = odom_seq++;
        write(odom_channel, msg);
      }
      if (std::hypot(l.base_from_laser_x_m, l.base_from_laser_y_m) > 1e-6 ||
          std::abs(l.base_from_laser_yaw_rad) > 1e-6) {
        ++laser_offsets;
      }
      laser_scan_t msg = slam::ToScanMessage(l);
      msg.header.seq = scan_seq++;
      write(scan_channel, msg);
    };
    int64_t file_bytes = 0;
    if (FILE* f = std::fopen(input.c_str(), "rb")) {
      std::fseek(f, 0, SEEK_END);
      file_bytes = std::ftell(f);
      std::fclose(f);
    }
    reader.on_progress = [&](int64_t bytes) {
      std::fprintf(stderr, "\rimport-carmen: %5.1f %%",
                   file_bytes ? 100.0 * bytes / file_bytes : 0.0);
    };
    const slam::CarmenStats stats = slam::ReadCarmenFile(input, &reader);
    std::fprintf(stderr, "\rimport-carmen: 100.0 %%\n");
    std::printf(
        "%s -> %s: %lld odometry, %lld scans, %lld comment lines, %lld other message lines, "
        "%lld malformed\n",
        input.c_str(), output.c_str(), (long long)odom_seq, (long long)scan_seq,
        (long long)stats.skipped_comments, (long long)stats.skipped_unknown,
        (long long)stats.malformed);
    if (laser_offsets > 0) {
      SARMAP_LOG(WARN)
          << laser_offsets << " ROBOTLASER1 scans have a laser offset from the robot; "
          << "laser_scan_t is in the laser frame: set the SLAM base_from_laser options";
    }
    return 0;
  });
}
