// bench_sim_vision: the people detector on the simulator's lab, lit and dark (issue 7's
// simulated acceptance). Renders frames along the robot's scripted path, detects people, and
// prints frame recall of the fully visible people (a detection within 0.5 m on the floor),
// false positives per frame, the same after k-of-n confirmation, and the detector's CPU time.
// Prints figures; asserts nothing (sim_vision_test asserts them).
//   bench_sim_vision [--verbose] [--world NAME]... [--step S] [--seed N] [--set key=value]...
//                    [--camera-height M --camera-tilt-deg D | --sweep]
// --camera-height/--camera-tilt-deg mount the simulated camera elsewhere (tilt: down
// positive) while the detector keeps config/robot.yaml's mounting; --sweep runs every world
// with the camera at 0.3, 0.55, 0.9, 1.2, 1.5 m and tilted -20, -10, 0, 10, 20 deg and prints
// the totals per posture.
#include "tools/sim_vision_eval.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  sarmap::sim_vision::EvalOptions eval;
  std::vector<std::string> worlds;
  bool sweep = false;
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
    } else if (arg == "--camera-height" && i + 1 < argc) {
      eval.camera_height_m = std::stod(argv[++i]);
    } else if (arg == "--camera-tilt-deg" && i + 1 < argc) {
      eval.camera_tilt_down_deg = std::stod(argv[++i]);
    } else if (arg == "--sweep") {
      sweep = true;
    } else if (arg == "--step" && i + 1 < argc) {
      eval.step_s = std::stod(argv[++i]);
    } else {
      fprintf(stderr,
              "usage: bench_sim_vision [--verbose] [--world name]... [--step seconds] [--seed n] "
              "[--set key=value]...\n"
              "                        [--camera-height m --camera-tilt-deg d | --sweep]\n");
      return 2;
    }
  }
  if (worlds.empty()) worlds = {"lab_lit", "lab_dark"};
  auto print = [](const std::string& label, const sarmap::sim_vision::Figures& f) {
    printf("%-34s frames %3d  visible %3d  found %3d  recall %.3f  FP/frame %.3f |", label.c_str(),
           f.frames, f.visible, f.found, f.recall(), f.fp_per_frame());
    const char* names[3] = {"standing", "sitting", "lying"};
    for (int k = 0; k < 3; ++k)
      printf(" %s %d/%d", names[k], f.by_posture[k].found, f.by_posture[k].visible);
    printf(" | %d-of-%d confirmed: recall %.3f FP/frame %.3f | detect cpu %.1f ms mean, %.1f max",
           f.confirm_k, f.confirm_n, f.confirmed_recall(), f.confirmed_fp_per_frame(),
           f.detect_cpu_ms_mean, f.detect_cpu_ms_max);
    if (f.placed > 0) {
      printf(" | placed: range bias %+.3f m, rms along %.3f across %.3f m", f.range_bias_m(),
             std::sqrt(f.range_error_sq_sum_m2 / f.placed),
             std::sqrt(f.cross_error_sq_sum_m2 / f.placed));
    }
    printf("\n");
    fflush(stdout);
  };
  try {
    std::vector<std::pair<double, double>> mountings = {
        {eval.camera_height_m, eval.camera_tilt_down_deg}};
    if (sweep) {
      mountings.clear();
      for (double h : {0.3, 0.55, 0.9, 1.2, 1.5}) {
        for (double t : {-20.0, -10.0, 0.0, 10.0, 20.0}) mountings.emplace_back(h, t);
      }
    }
    for (const std::string& world : worlds) {
      sarmap::sim_vision::Figures total;
      int runs = 0;
      for (const auto& [h, t] : mountings) {
        eval.world = world;
        eval.camera_height_m = h;
        eval.camera_tilt_down_deg = t;
        const auto f = sarmap::sim_vision::Evaluate(eval);
        char label[96];
        if (h >= 0) {
          snprintf(label, sizeof label, "%s h %.2f tilt %+.0f", world.c_str(), h, t);
        } else {
          snprintf(label, sizeof label, "%s", world.c_str());
        }
        print(label, f);
        total.frames += f.frames;
        total.visible += f.visible;
        total.found += f.found;
        total.false_positives += f.false_positives;
        total.confirm_k = f.confirm_k;
        total.confirm_n = f.confirm_n;
        total.confirmed_found += f.confirmed_found;
        total.confirmed_false_positives += f.confirmed_false_positives;
        total.detect_cpu_ms_mean += f.detect_cpu_ms_mean;
        total.detect_cpu_ms_max = std::max(total.detect_cpu_ms_max, f.detect_cpu_ms_max);
        for (int k = 0; k < 3; ++k) {
          total.by_posture[k].visible += f.by_posture[k].visible;
          total.by_posture[k].found += f.by_posture[k].found;
        }
        ++runs;
      }
      if (runs > 1) {
        total.detect_cpu_ms_mean /= runs;
        print(world + " TOTAL", total);
      }
    }
  } catch (const std::exception& e) {
    fprintf(stderr, "bench_sim_vision: %s\n", e.what());
    return 1;
  }
  return 0;
}
