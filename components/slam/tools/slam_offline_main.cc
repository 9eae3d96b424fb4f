// sarmap-slam-offline: runs the SLAM core over a whole dataset as fast as possible (one core)
// and writes the trajectory of every scan; reads CARMEN logs directly or LCM logs (ODOM, SCAN).

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/decode.h"
#include "common/logging.h"
#include "log-tools/lcm_log_reader.h"
#include "slam/carmen.h"
#include "slam/map_io.h"
#include "slam/messages.h"
#include "slam/slam.h"
#include "slam/slam_node_options.h"

using namespace sarmap;

namespace {

struct Input {
  bool is_scan = false;
  slam::LaserScan scan;
  double odom_time_s = 0;
  slam::Rigid2d odom;
};

Input OdometryInput(double time_s, const slam::Rigid2d& odom) {
  Input in;
  in.odom_time_s = time_s;
  in.odom = odom;
  return in;
}

bool EndsWith(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}

std::vector<Input> ReadInput(const std::string& path, const slam::SlamNodeOptions& options,
                             bool* is_carmen) {
  std::vector<Input> inputs;
  *is_carmen = false;
  if (EndsWith(path, ".log") || EndsWith(path, ".clf") || EndsWith(path, ".carmen")) {
    // CARMEN text log (unless it is an LCM log with a .log name: LCM logs start with a magic).
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw std::runtime_error("cannot open '" + path + "'");
    unsigned char magic[4] = {0, 0, 0, 0};
    const size_t got = std::fread(magic, 1, 4, f);
    std::fclose(f);
    const bool lcm_magic =
        got == 4 && magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01;
    if (!lcm_magic) {
      slam::CarmenReader reader;
      reader.warn = [](const std::string& w) { SARMAP_LOG(WARN) << "CARMEN: " << w; };
      reader.on_odometry = [&](const slam::CarmenOdometry& o) {
        inputs.push_back(OdometryInput(o.time_s, slam::Rigid2d(o.x_m, o.y_m, o.theta_rad)));
      };
      reader.on_laser = [&](const slam::CarmenLaser& l) {
        if (l.has_odometry) {
          inputs.push_back(OdometryInput(
              l.time_s, slam::Rigid2d(l.odometry.x_m, l.odometry.y_m, l.odometry.theta_rad)));
        }
        Input in;
        in.is_scan = true;
        in.scan.time_s = l.time_s;
        in.scan.angle_min_rad = l.angle_min_rad;
        in.scan.angle_increment_rad = l.angle_increment_rad;
        in.scan.range_min_m = 0;
        in.scan.range_max_m = std::nextafter(static_cast<float>(l.range_max_m), 0.f);
        in.scan.ranges_m = l.ranges_m;
        if (l.source == "ROBOTLASER1") {  // the line carries the laser's pose on the robot
          in.scan.has_base_from_laser = true;
          in.scan.base_from_laser = slam::Rigid2d(l.base_from_laser_x_m, l.base_from_laser_y_m,
                                                  l.base_from_laser_yaw_rad);
        }
        inputs.push_back(std::move(in));
      };
      slam::ReadCarmenFile(path, &reader);
      *is_carmen = true;
      return inputs;
    }
  }
  // Read past damage (a truncated or corrupt log): what is readable is used, where it breaks is
  // a warning.
  logtools::LcmLogReader log(path);
  logtools::LogEvent event;
  int64_t bad = 0;
  while (log.Next(&event)) {
    const logtools::LogEvent* ev = &event;
    if (ev->channel == options.scan_channel) {
      laser_scan_t msg;
      if (!common::DecodeMessage(ev->data.data(), ev->data.size(), &msg)) {
        ++bad;
        continue;
      }
      Input in;
      in.is_scan = true;
      in.scan = slam::FromScanMessage(msg);
      inputs.push_back(std::move(in));
    } else if (ev->channel == options.odom_channel) {
      odometry_t msg;
      if (!common::DecodeMessage(ev->data.data(), ev->data.size(), &msg)) {
        ++bad;
        continue;
      }
      inputs.push_back(
          OdometryInput(common::UtimeToSeconds(msg.header.utime), slam::FromOdometryMessage(msg)));
    }
  }
  for (const auto& p : log.problems()) SARMAP_LOG(WARN) << logtools::DescribeProblem(p);
  if (bad) {
    SARMAP_LOG(WARN) << bad << " undecodable events skipped";
  }
  return inputs;
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-slam-offline", [&]() -> int {
    std::string input, output, map_prefix, save_path, config, live_output;
    std::vector<std::string> overrides;
    bool print_config = false, quiet = false, no_final = false, log_order = false,
         time_order = false;
    common::ArgParser args("sarmap-slam-offline",
                           "Runs SLAM over a CARMEN or LCM log as fast as possible and writes "
                           "the trajectory (t x y yaw per scan).");
    args.AddPositional("LOG", &input, "CARMEN log (.log/.clf) or LCM log (ODOM + SCAN)");
    args.AddFlag("--output", &output, "trajectory file to write (t x y yaw)");
    args.AddFlag(
        "--live-output", &live_output,
        "also write each scan's pose as the node publishes it on POSE, at that time (t x y yaw)");
    args.AddFlag("--config", &config, "options YAML (config/slam.yaml)");
    args.AddRepeated("--set", &overrides,
                     "override an option, e.g. --set slam.local.resolution_m=0.05");
    args.AddFlag("--map", &map_prefix, "write the map as PREFIX.pgm + PREFIX.yaml");
    args.AddFlag("--save", &save_path, "write the pose-graph file here");
    args.AddSwitch("--print-config", &print_config, "print the effective options and exit");
    args.AddSwitch("--quiet", &quiet, "no progress output");
    args.AddSwitch("--log-order", &log_order,
                   "process inputs in log order (the default for CARMEN logs: their line order is "
                   "the recording order)");
    args.AddSwitch("--time-order", &time_order,
                   "process inputs in time order (the default for LCM logs, as the node's "
                   "time-ordered queue does)");
    args.AddSwitch("--no-final-optimisation", &no_final,
                   "skip the optimisation at the end (to see local SLAM alone)");
    if (!args.Parse(argc, argv)) return 0;
    const auto options = common::LoadOptions<slam::SlamNodeOptions>(config, overrides);
    if (print_config) {
      std::printf("%s", common::OptionsToYaml(options, true).c_str());
      return 0;
    }
    if (output.empty()) throw common::ArgError("--output is required");

    auto start = std::chrono::steady_clock::now();
    if (log_order && time_order)
      throw common::ArgError("--log-order and --time-order exclude each other");
    bool is_carmen = false;
    std::vector<Input> inputs = ReadInput(input, options, &is_carmen);
    // A CARMEN log's lines are in recording order; its stamps are not always (Intel has 631
    // scans stamped up to 0.9 s before the scan above them, and its relations follow the line
    // order), so CARMEN logs are processed in line order by default. An LCM log is sorted by
    // time, as the node's time-ordered queue does.
    if (time_order || (!log_order && !is_carmen)) {
      std::stable_sort(inputs.begin(), inputs.end(), [](const Input& a, const Input& b) {
        return (a.is_scan ? a.scan.time_s : a.odom_time_s) <
               (b.is_scan ? b.scan.time_s : b.odom_time_s);
      });
    }
    const double read_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    double first_t = 0, last_t = 0;
    int64_t num_scans = 0;
    for (const auto& in : inputs) {
      if (!in.is_scan) continue;
      if (num_scans++ == 0) first_t = in.scan.time_s;
      last_t = in.scan.time_s;
    }
    std::fprintf(stderr, "read %zu inputs (%lld scans, %.1f s of data) in %.2f s\n", inputs.size(),
                 (long long)num_scans, last_t - first_t, read_s);
    if (num_scans == 0) {
      throw std::runtime_error(
          "no laser scan in '" + input + "'" +
          (is_carmen ? std::string(" (CARMEN: FLASER, RAWLASER1 or ROBOTLASER1 lines)")
                     : " (LCM log: laser_scan_t on " + options.scan_channel + ")"));
    }

    slam::Slam slam(options.slam);
    std::vector<double> latencies;
    latencies.reserve(num_scans);
    start = std::chrono::steady_clock::now();
    int64_t done = 0, rejected_scans = 0, rejected_odom = 0;
    int last_percent = -1;
    std::vector<std::pair<double, slam::Rigid2d>> live_poses;
    for (const auto& in : inputs) {
      if (!in.is_scan) {
        std::string why;
        if (!slam.AddOdometry(in.odom_time_s, in.odom, &why)) {
          if (++rejected_odom <= 5) {
            SARMAP_LOG(WARN) << "odometry rejected: " << why;
          }
        }
        continue;
      }
      const auto t0 = std::chrono::steady_clock::now();
      const slam::ScanResult r = slam.AddScan(in.scan);
      latencies.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      if (r.accepted) live_poses.emplace_back(in.scan.time_s, r.map_from_base);
      if (!r.accepted && ++rejected_scans <= 5) {
        SARMAP_LOG(WARN) << "scan rejected: " << r.reason;
      }
      ++done;
      const int percent = static_cast<int>(100 * done / std::max<int64_t>(1, num_scans));
      if (!quiet && percent != last_percent) {
        last_percent = percent;
        const auto& s = slam.stats();
        const double el =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::fprintf(stderr,
                     "\r%3d %%  scans %lld  nodes %d  submaps %d  loops %lld/%lld  "
                     "optimisations %lld  %.1f s (%.1fx real time)   ",
                     percent, (long long)s.scans, slam.num_live_nodes(), slam.num_live_submaps(),
                     (long long)s.loop_closures, (long long)s.loop_searches,
                     (long long)s.optimisations, el,
                     el > 0 ? (in.scan.time_s - first_t) / el : 0.0);
      }
    }
    const auto t_final = std::chrono::steady_clock::now();
    if (!no_final) slam.Optimise();
    const double final_opt_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_final).count();
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!quiet) std::fprintf(stderr, "\n");
    slam::SaveTrajectory(output, slam.Trajectory());
    if (!live_output.empty()) {
      FILE* f = std::fopen(live_output.c_str(), "w");
      if (!f) throw std::runtime_error("cannot write " + live_output);
      std::fprintf(f, "# t_s x_m y_m yaw_rad (map_from_base as published live)\n");
      for (const auto& [t, p] : live_poses) {
        std::fprintf(f, "%.6f %.6f %.6f %.6f\n", t, p.translation().x(), p.translation().y(),
                     p.yaw_rad());
      }
      std::fclose(f);
    }

    std::sort(latencies.begin(), latencies.end());
    auto pct = [&](double p) {
      return latencies.empty()
                 ? 0.0
                 : latencies[std::min(latencies.size() - 1, size_t(p * latencies.size()))];
    };
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    const auto& s = slam.stats();
    std::printf("dataset %s\n", input.c_str());
    std::printf(
        "scans %lld (rejected %lld, out of time order %lld, standing still %lld), "
        "odometry rejected %lld, nodes %lld (%d live), submaps %lld (%d live)\n",
        (long long)s.scans, (long long)s.rejected_scans, (long long)s.reordered_scans,
        (long long)s.stopped_scans, (long long)s.rejected_odometry, (long long)s.nodes,
        slam.num_live_nodes(), (long long)s.submaps, slam.num_live_submaps());
    std::printf(
        "loop closures %lld of %lld searches (%lld inconsistent with the graph rejected, %lld on "
        "the window's boundary rejected, %lld precomputation stacks built), optimisations %lld\n",
        (long long)s.loop_closures, (long long)s.loop_searches,
        (long long)s.loop_closures_inconsistent, (long long)s.loop_closures_at_window_edge,
        (long long)s.precomputations_built, (long long)s.optimisations);
    if (s.submaps_trimmed + s.submaps_kept_new_area + s.submaps_kept_new_obstacles > 0) {
      std::printf(
          "trimming: %lld submaps trimmed (%lld with new obstacles, over their budget), %lld kept "
          "for their new area, %lld for new obstacles only; %lld nodes trimmed\n",
          (long long)s.submaps_trimmed, (long long)s.submaps_trimmed_over_obstacle_budget,
          (long long)s.submaps_kept_new_area, (long long)s.submaps_kept_new_obstacles,
          (long long)s.nodes_trimmed);
    }
    std::printf(
        "data %.1f s, processing %.2f s (local %.2f, loop search %.2f, optimisation %.2f, final "
        "%.2f) "
        "= %.1fx real time\n",
        last_t - first_t, wall_s, s.local_seconds, s.loop_seconds, s.optimise_seconds, final_opt_s,
        wall_s > 0 ? (last_t - first_t) / wall_s : 0.0);
    std::printf("per-scan latency: median %.2f ms, p99 %.2f ms, max %.2f ms\n", 1e3 * pct(0.5),
                1e3 * pct(0.99), 1e3 * latencies.back());
    std::printf("peak memory (max RSS) %.1f MB\n", ru.ru_maxrss / 1024.0);
    const slam::Slam::MemoryUsage m = slam.Memory();
    std::printf(
        "SLAM data at the end %.1f MB: submap grids %.1f, precomputations %.1f, live nodes %.1f, "
        "trimmed nodes %.1f, trimmed submaps %.1f, graph %.1f, trajectory %.1f\n",
        m.Total() / 1048576.0, m.submap_grids / 1048576.0, m.precomputations / 1048576.0,
        m.live_nodes / 1048576.0, m.trimmed_nodes / 1048576.0, m.trimmed_submaps / 1048576.0,
        m.graph / 1048576.0, m.trajectory / 1048576.0);
    const double cpu_s = ru.ru_utime.tv_sec + 1e-6 * ru.ru_utime.tv_usec + ru.ru_stime.tv_sec +
                         1e-6 * ru.ru_stime.tv_usec;
    std::printf("CPU time (one thread, incl. reading) %.2f s = %.1fx real time\n", cpu_s,
                cpu_s > 0 ? (last_t - first_t) / cpu_s : 0.0);
    std::printf("trajectory: %s\n", output.c_str());
    if (!map_prefix.empty()) {
      const slam::OccupancyMap map = slam.RenderMap();
      slam::SaveMapServerMap(map, map_prefix);
      // A PNG for people (grey unknown, darker = more likely occupied; top row = highest y).
      cv::Mat img(map.height, map.width, CV_8UC1);
      for (int y = 0; y < map.height; ++y) {
        for (int x = 0; x < map.width; ++x) {
          const int v = map.cells[static_cast<size_t>(y) * map.width + x];
          img.at<uint8_t>(map.height - 1 - y, x) =
              v < 0 ? 205 : static_cast<uint8_t>(255 - v * 255 / 100);
        }
      }
      cv::imwrite(map_prefix + ".png", img);
      std::printf("map: %s.pgm %s.yaml %s.png\n", map_prefix.c_str(), map_prefix.c_str(),
                  map_prefix.c_str());
    }
    if (!save_path.empty()) {
      slam.Save(save_path);
      std::printf("pose graph: %s\n", save_path.c_str());
    }
    return 0;
  });
}
