// bench_sim_vision: the people detector on the simulator's lab, lit and dark (issue 7's
// simulated acceptance). Renders frames along the robot's scripted path, detects people, and
// prints frame recall of the fully visible people (a detection within 0.5 m on the floor),
// false positives per frame, the same after k-of-n confirmation, and the detector's CPU time.
// Prints figures; asserts nothing (sim_vision_test asserts them).
//   bench_sim_vision [--verbose] [--world NAME]... [--step S] [--seed N] [--set key=value]...
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "tools/sim_vision_eval.h"

int main(int argc, char** argv) {
  sarmap::sim_vision::EvalOptions eval;
  std::vector<std::string> worlds;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--verbose") {
      eval.verbose = true;
    } else if (arg == "--set" && i + 1 < argc) {
      eval.overrides.push_back(argv[++i]);
    } else if (arg == "--world" && i + 1 < argc) {
      worlds.push_back(argv[++i]);
    } else if (arg == "--seed" && i + 1 < argc) {
      eval.seed = std::stoll(argv[++i]);
    } else if (arg == "--step" && i + 1 < argc) {
      eval.step_s = std::stod(argv[++i]);
    } else {
      fprintf(stderr, "usage: bench_sim_vision [--verbose] [--world name]... [--step seconds] [--seed n] [--set key=value]...\n");
      return 2;
    }
  }
  if (worlds.empty()) worlds = {"lab_lit", "lab_dark"};
  try {
    for (const std::string& world : worlds) {
      eval.world = world;
      const auto f = sarmap::sim_vision::Evaluate(eval);
      printf("%-9s frames %3d  fully visible person-frames %3d  found %3d  frame recall %.3f  "
             "false positives/frame %.3f | %d-of-%d confirmed: recall %.3f  FP/frame %.3f | detect cpu %.1f ms "
             "mean, %.1f max\n",
             world.c_str(), f.frames, f.visible, f.found, f.recall(), f.fp_per_frame(), f.confirm_k, f.confirm_n, f.confirmed_recall(),
             f.confirmed_fp_per_frame(), f.detect_cpu_ms_mean, f.detect_cpu_ms_max);
      fflush(stdout);
    }
  } catch (const std::exception& e) {
    fprintf(stderr, "bench_sim_vision: %s\n", e.what());
    return 1;
  }
  return 0;
}
