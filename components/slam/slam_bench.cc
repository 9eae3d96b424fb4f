// bench_slam: runs sarmap-slam-offline on Intel, ACES and MIT-CSAIL with config/slam.yaml, and on
// Intel interlaced and driven twice (sarmap-log-interlace-carmen --laps 2), and evaluates each
// trajectory with sarmap-log-eval-relations. Prints accuracy (all four
// metrics), speed as a multiple of real time (CPU time of the single-threaded run, and wall
// time), per-scan latency percentiles and peak memory. Takes several minutes.

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
  const std::string bin = SARMAP_BIN_DIR;
  const std::string data = std::string(SARMAP_DATA_DIR) + "/slam";
  const std::string config = std::string(SARMAP_SOURCE_DIR) + "/config/slam.yaml";
  if (argc > 2 || (argc == 2 && argv[1][0] == '-')) {
    std::printf(
        "usage: bench_slam [OUT_DIR]\n\n"
        "Runs sarmap-slam-offline on the Intel, ACES and MIT-CSAIL laser logs and on Intel\n"
        "interlaced over 2 laps (from the shared data), then sarmap-log-eval-relations on each;\n"
        "trajectories, maps and plots go to OUT_DIR (default /tmp).\n");
    return std::strcmp(argv[1], "-h") == 0 || std::strcmp(argv[1], "--help") == 0 ? 0 : 2;
  }
  const std::string out_dir = argc > 1 ? argv[1] : "/tmp";
  struct Dataset {
    const char* name;
    const char* log;
    const char* relations;
  } datasets[] = {{"intel", "intel/intel.log", "intel/intel.relations"},
                  {"aces", "aces/aces.log", "aces/aces.relations"},
                  {"mit-csail", "mit-csail/mit-csail.clf", "mit-csail/mit-csail.relations"}};
  int failures = 0;
  for (const Dataset& d : datasets) {
    const std::string log = data + "/" + d.log;
    if (!std::ifstream(log)) {
      std::printf("=== %s: shared data missing (%s), skipped\n", d.name, log.c_str());
      continue;
    }
    const std::string traj = out_dir + "/bench_slam_" + d.name + ".txt";
    const std::string run = bin + "/sarmap-slam-offline " + log + " --config " + config +
                            " --output " + traj + " --quiet --map " + out_dir + "/bench_slam_" +
                            d.name;
    const std::string eval = bin + "/sarmap-log-eval-relations " + traj + " " + data + "/" +
                             d.relations + " --plot " + out_dir + "/bench_slam_" + d.name +
                             ".png 2>/dev/null";
    std::printf("=== %s\n$ %s\n", d.name, run.c_str());
    std::fflush(stdout);
    if (std::system(run.c_str()) != 0) ++failures;
    std::printf("$ %s\n", eval.c_str());
    std::fflush(stdout);
    if (std::system(eval.c_str()) != 0) ++failures;
    std::fflush(stdout);
  }
  // An interlacing scanner over a long mission: Intel re-cut into four interlaced sweeps and
  // driven twice (90 min, about 1.35 km; the log ends 0.2 m from its start).
  const std::string intel = data + "/intel/intel.log";
  if (std::ifstream(intel)) {
    const std::string log = out_dir + "/bench_slam_intel_interlaced_2laps.log";
    const std::string relations = out_dir + "/bench_slam_intel_interlaced_2laps.relations";
    const std::string traj = out_dir + "/bench_slam_intel_interlaced_2laps.txt";
    const std::string cut = bin + "/sarmap-log-interlace-carmen " + intel + " " + log +
                            " --laps 2 --relations " + data + "/intel/intel.relations" +
                            " --relations-output " + relations;
    const std::string run = bin + "/sarmap-slam-offline " + log + " --config " + config +
                            " --output " + traj + " --quiet";
    const std::string eval =
        bin + "/sarmap-log-eval-relations " + traj + " " + relations + " 2>/dev/null";
    for (const std::string& cmd : {cut, run, eval}) {
      std::printf("$ %s\n", cmd.c_str());
      std::fflush(stdout);
      if (std::system(cmd.c_str()) != 0) ++failures;
      std::fflush(stdout);
    }
  }
  std::printf(
      "Cartographer (Hess et al. 2016) mean abs trans: Intel 0.0229 m, ACES 0.0375 m, "
      "MIT-CSAIL 0.0319 m; abs rot goal <= 0.45 deg.\n");
  return failures ? 1 : 0;
}
