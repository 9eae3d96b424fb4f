// sarmap-mission-bench: autonomous missions in one process, in simulated time
// (mission_runner.h), on generated incident sites or given worlds; prints a table per site and
// mode and writes each run's explored-area curve.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "common/args.h"
#include "common/node_main.h"
#include "log-tools/mission_metrics.h"
#include "mission/mission_runner.h"
#include "sim/floor_plan.h"
#include "sim/site_generator.h"
#include "sim/world.h"

namespace {

using namespace sarmap;

// Feeds the mission's messages to the same metrics as `sarmap-log report`, and notes when each
// person was first in the camera's view.
class Metrics : public mission::MissionObserver {
 public:
  void OnTruth(double t_s, const sim_truth_t& m) override {
    metrics.OnTruth(m.header.utime, m);
    for (const auto& p : m.people) {
      if (p.visible_to_camera && !in_view_s.count(p.id)) in_view_s[p.id] = t_s;
    }
    people = static_cast<int>(m.people.size());
  }
  void OnFloor(double, const occupancy_grid_t& m) override { metrics.OnFloor(m.header.utime, m); }
  void OnMap(double, const occupancy_grid_t& m) override { metrics.OnMap(m.header.utime, m); }
  void OnExploreStatus(double, const explore_status_t& m) override { metrics.OnExploreStatus(m.header.utime, m); }
  logtools::MissionMetrics metrics;
  std::map<int64_t, double> in_view_s;
  int people = 0;
};

struct Row {
  std::string site, lighting, mode;
  double reachable_m2 = 0, mapped_fraction = 0, rate_m2_per_min = 0, t90_s = -1;
  int collisions = 0;
  double longest_stuck_s = 0;
  bool home = false;
  double home_s = -1;
  int in_view = 0, people = 0;
  double distance_m = 0, cpu_s = 0, explore_cpu_percent = 0, simulated_s = 0;
  double trail_rms_m = 0, trail_max_m = 0;  // SLAM pose against truth, aligned by the start pose
};

// SLAM's trail error over the mission's samples, with the truth taken into the map frame by the
// start pose as `sarmap-log report` does; writes the aligned trails to `csv_path`.
void TrailError(const mission::MissionResult& r, const common::Rigid2d& world_from_map,
                const std::string& csv_path, Row* row) {
  const common::Rigid2d map_from_world = world_from_map.inverse();
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
  std::ofstream csv(csv_path);
  csv << "time_s,truth_x_m,truth_y_m,truth_yaw_rad,slam_x_m,slam_y_m,slam_yaw_rad,error_m\n";
  for (const mission::MissionSample& s : r.samples) {
    pairs.emplace_back(s.slam_pose.head<2>(), s.truth_pose.head<2>());
    const common::Rigid2d truth =
        map_from_world * common::Rigid2d(s.truth_pose.x(), s.truth_pose.y(), s.truth_pose.z());
    const double error_m = (truth.translation() - s.slam_pose.head<2>()).norm();
    row->trail_max_m = std::max(row->trail_max_m, error_m);
    csv << s.t_s << "," << truth.translation().x() << "," << truth.translation().y() << ","
        << truth.yaw_rad() << "," << s.slam_pose.x() << "," << s.slam_pose.y() << ","
        << s.slam_pose.z() << "," << error_m << "\n";
  }
  row->trail_rms_m = logtools::TrailResidualRms(map_from_world, pairs);
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-mission-bench", [&]() -> int {
    mission::MissionRunOptions run;
    std::string worlds, modes = "frontier,reactive", out_dir = "out/mission-bench", site_config = "config/site.yaml";
    int sites = 0, first_site = 1;
    common::ArgParser parser(
        "sarmap-mission-bench",
        "Autonomous missions in simulated time: the simulator, depth-to-scan, SLAM and the explorer\n"
        "in one process, as fast as the CPU allows, on generated incident sites (sarmap-site) or given\n"
        "worlds. For each site and exploration mode it prints the share of the reachable floor mapped,\n"
        "the coverage rate against the physical bound, collisions, the longest time without progress,\n"
        "whether the robot came home, and when each person was first in the camera's view; each run's\n"
        "explored-area curve goes to OUT/<site>-<mode>.csv, the explorer's final grid to\n"
        "OUT/<site>-<mode>-explorer.pgm, SLAM's trail against the truth (aligned by the start\n"
        "pose, as sarmap-log report does) to OUT/<site>-<mode>-trail.csv. The perception chain\n"
        "(people, sound) runs only in the live stack (make demo DEMO_SITE=N).");
    parser.AddFlag("--sites", &sites, "generated sites: this many seeds, from --first-site");
    parser.AddFlag("--first-site", &first_site, "first seed of the generated sites");
    parser.AddFlag("--site-config", &site_config, "generator options for the sites");
    parser.AddFlag("--worlds", &worlds, "comma-separated world files (instead of or besides the sites)");
    parser.AddFlag("--modes", &modes, "comma-separated exploration modes: frontier, reactive, sound_guided");
    parser.AddFlag("--duration", &run.duration_s, "simulated seconds per mission");
    parser.AddFlag("--camera-rate", &run.camera_rate_hz, "depth frames per simulated second");
    parser.AddFlag("--out", &out_dir, "folder for the generated worlds and the curves");
    parser.AddRepeated("--set-explore", &run.explore_overrides, "explorer option override (key=value)");
    parser.AddRepeated("--set-sim", &run.sim_overrides, "simulator option override (key=value)");
    parser.AddRepeated("--set-slam", &run.slam_overrides, "SLAM option override (key=value)");
    parser.AddRepeated("--set-depth", &run.depth_overrides, "depth-to-scan option override (key=value)");
    if (!parser.Parse(argc, argv)) return 0;
    if (sites <= 0 && worlds.empty()) throw common::ArgError("give --sites N or --worlds FILE[,FILE...]");
    ::mkdir(out_dir.c_str(), 0755);

    struct Target {
      std::string name, path, lighting;
    };
    std::vector<Target> targets;
    for (int seed = first_site; seed < first_site + sites; ++seed) {
      auto site = common::LoadOptions<sim::SiteOptions>(site_config, {"seed=" + std::to_string(seed)});
      const sim::World world = sim::GenerateSite(site);
      const std::string path = out_dir + "/site-" + std::to_string(seed) + ".yaml";
      std::ofstream(path) << sim::SiteHeader(site) << sim::WorldToYaml(world);
      targets.push_back({"site-" + std::to_string(seed), path, world.lights_on ? "lit" : "dark"});
    }
    for (const std::string& w : Split(worlds)) {
      const sim::World world = sim::LoadWorld(w);
      targets.push_back({world.name, w, world.lights_on ? "lit" : "dark"});
    }
    // The physical bound on the coverage rate: driving straight at full speed, the depth view
    // sweeps a swath as wide as its chord at the range limit.
    const double speed = 0.35, range = 4.5, hfov = 58.0 * M_PI / 180;
    const double bound = speed * 2 * range * std::sin(hfov / 2) * 60;

    std::vector<Row> rows;
    for (const Target& target : targets) {
      for (const std::string& mode : Split(modes)) {
        mission::MissionRunOptions o = run;
        o.world = target.path;
        o.mode = mode;
        o.explorer_map_pgm = out_dir + "/" + target.name + "-" + mode + "-explorer.pgm";
        o.slam_map_pgm = out_dir + "/" + target.name + "-" + mode + "-slam.pgm";
        Metrics metrics;
        std::fprintf(stderr, "%s %s:", target.name.c_str(), mode.c_str());
        const mission::MissionResult r = mission::RunMission(o, &metrics, [](double t) {
          if (static_cast<int>(t) % 60 == 0) std::fprintf(stderr, " %.0f", t);
        });
        std::fprintf(stderr, " s\n");
        const logtools::MissionMetricsResult m = metrics.metrics.Result();
        Row row;
        row.site = target.name;
        row.lighting = target.lighting;
        row.mode = mode;
        row.reachable_m2 = m.reachable_m2.value_or(0);
        row.mapped_fraction = m.mapped_fraction.value_or(0);
        // Rate over the first 5 minutes (or the mission if shorter): m^2 mapped per minute.
        double at = 0, at_t = 0;
        for (const auto& p : m.coverage) {
          if (p.time_s <= 300.0 + 1e-6) {
            at = p.mapped_m2;
            at_t = p.time_s;
          }
          if (row.t90_s < 0 && p.fraction >= 0.9) row.t90_s = p.time_s;
        }
        row.rate_m2_per_min = at_t > 0 ? at / (at_t / 60) : 0;
        row.collisions = r.collisions;
        for (const std::string& c : r.contacts) std::fprintf(stderr, "  %s %s collision %s\n", target.name.c_str(), mode.c_str(), c.c_str());
        row.longest_stuck_s = m.longest_stuck_s.value_or(0);
        row.home = r.came_home;
        row.home_s = r.home_after_s;
        row.in_view = static_cast<int>(metrics.in_view_s.size());
        row.people = metrics.people;
        row.distance_m = r.distance_m;
        row.cpu_s = r.cpu_s;
        row.simulated_s = r.simulated_s;
        row.explore_cpu_percent = r.simulated_s > 0 ? 100 * r.explore_cpu_s / r.simulated_s : 0;
        rows.push_back(row);
        std::ofstream curve(out_dir + "/" + target.name + "-" + mode + ".csv");
        curve << "time_s,mapped_m2,fraction\n";
        for (const auto& p : m.coverage) curve << p.time_s << "," << p.mapped_m2 << "," << p.fraction << "\n";
        Row& last = rows.back();
        const std::string trail_csv = out_dir + "/" + target.name + "-" + mode + "-trail.csv";
        TrailError(r, m.world_from_map, trail_csv, &last);
        std::fprintf(stderr, "  trail RMS %.3f m, max %.2f m, mapped %.1f %%, collisions %d\n",
                     last.trail_rms_m, last.trail_max_m, 100 * last.mapped_fraction,
                     last.collisions);
      }
    }

    std::printf("\n| site | light | mode | reachable m^2 | mapped | m^2/min (first 5 min) | 90 %% after | collisions | "
                "longest stuck | home | people in view | driven | explorer CPU |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows) {
      std::printf("| %s | %s | %s | %.0f | %.1f %% | %.1f | %s | %d | %.0f s | %s | %d/%d | %.0f m | %.1f %% |\n",
                  r.site.c_str(), r.lighting.c_str(), r.mode.c_str(), r.reachable_m2, 100 * r.mapped_fraction,
                  r.rate_m2_per_min, r.t90_s < 0 ? "-" : (std::to_string(static_cast<int>(r.t90_s)) + " s").c_str(),
                  r.collisions, r.longest_stuck_s,
                  r.home ? (std::to_string(static_cast<int>(r.home_s)) + " s").c_str() : "no", r.in_view, r.people,
                  r.distance_m, r.explore_cpu_percent);
    }
    std::printf("\nSLAM trail against the truth (aligned by the start pose, as sarmap-log report):\n");
    std::printf("| site | mode | trail RMS | trail max | mapped | collisions |\n|---|---|---|---|---|---|\n");
    for (const Row& r : rows) {
      std::printf("| %s | %s | %.3f m | %.2f m | %.1f %% | %d |\n", r.site.c_str(), r.mode.c_str(),
                  r.trail_rms_m, r.trail_max_m, 100 * r.mapped_fraction, r.collisions);
    }
    std::printf("\ncoverage-rate bound: %.0f m^2/min (%.2f m/s x %.1f m, the depth view's width at %.1f m)\n", bound,
                speed, 2 * range * std::sin(hfov / 2), range);
    for (const std::string& mode : Split(modes)) {
      std::vector<double> mapped;
      int home = 0, collisions = 0;
      double stuck = 0;
      for (const Row& r : rows) {
        if (r.mode != mode) continue;
        mapped.push_back(r.mapped_fraction);
        home += r.home;
        collisions += r.collisions;
        stuck = std::max(stuck, r.longest_stuck_s);
      }
      if (mapped.empty()) continue;
      std::sort(mapped.begin(), mapped.end());
      const double median = mapped.size() % 2 ? mapped[mapped.size() / 2]
                                              : 0.5 * (mapped[mapped.size() / 2 - 1] + mapped[mapped.size() / 2]);
      std::printf("%s: median mapped %.1f %% over %zu runs, home %d, collisions %d, longest stuck %.0f s\n",
                  mode.c_str(), 100 * median, mapped.size(), home, collisions, stuck);
    }
    return 0;
  });
}
