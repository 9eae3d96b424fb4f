// sarmap-mission-bench: autonomous missions in one process, in simulated time (mission_runner.h).
#include <cstdio>

#include "common/args.h"
#include "common/node_main.h"
#include "mission/mission_runner.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-mission-bench", [&]() -> int {
    using namespace sarmap;
    mission::MissionRunOptions options;
    common::ArgParser parser("sarmap-mission-bench",
                             "Runs autonomous missions in simulated time (simulator, depth-to-scan, SLAM and the\n"
                             "explorer in one process) and prints what they achieved.");
    parser.AddFlag("--world", &options.world, "world file");
    parser.AddFlag("--mode", &options.mode, "exploration mode (frontier, sound_guided, reactive); default: the config's");
    parser.AddFlag("--duration", &options.duration_s, "simulated seconds");
    parser.AddFlag("--seed", &options.seed, "simulator seed");
    parser.AddFlag("--camera-rate", &options.camera_rate_hz, "depth frames per simulated second");
    parser.AddRepeated("--set-explore", &options.explore_overrides, "explore option override (key=value)");
    parser.AddFlag("--explorer-map", &options.explorer_map_pgm, "write the explorer's final grid (PGM) here");
    if (!parser.Parse(argc, argv)) return 0;
    const mission::MissionResult r = mission::RunMission(options, nullptr, [](double t) {
      std::fprintf(stderr, "\r  %.0f s simulated", t);
    });
    std::fprintf(stderr, "\n");
    for (const auto& s : r.samples) {
      if (static_cast<int>(s.t_s) % 10 != 0) continue;
      std::printf("t %5.0f  truth %6.2f %6.2f  slam %6.2f %6.2f  %-14s dist %6.1f coll %d\n", s.t_s, s.truth_pose.x(),
                  s.truth_pose.y(), s.slam_pose.x(), s.slam_pose.y(), s.state.c_str(), s.distance_m, s.collisions);
    }
    std::printf("simulated %.0f s, CPU %.1f s (explorer %.2f s), distance %.1f m, collisions %d, recoveries %d, %s\n",
                r.simulated_s, r.cpu_s, r.explore_cpu_s, r.distance_m, r.collisions, r.recoveries,
                r.final_state.c_str());
    return 0;
  });
}
