// Benchmark of the launcher (prints figures, asserts nothing):
//  1. time from `start` to all of 10 commands reported running, with a sheriff that already
//     knows the deputy (in-process Sheriff) and end to end through the CLI (which first has to
//     learn the deputy's state: it probes for PM_INFO);
//  2. CPU of an idle deputy supervising 20 running commands (from /proc, over 10 s), while a
//     live sheriff re-sends the desired state every second.
// Runs inside a private network namespace (sarmap_add_bench ... NETNS).
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <vector>

#include "common/node.h"
#include "common/options.h"
#include "procman/event_loop.h"
#include "procman/process_table.h"
#include "procman/sheriff.h"
#include "procman/test_support.h"

using namespace sarmap::procman;
using namespace sarmap::procman::testing;

namespace {

std::string MakeConfig(const std::string& deputy, int n, int marker) {
  std::string text = "group \"bench\" {\n";
  for (int i = 0; i < n; ++i) {
    text += "  cmd \"c" + std::to_string(i) + "\" { exec = \"sleep " + std::to_string(marker + i) +
            "\"; deputy = \"" + deputy + "\"; }\n";
  }
  return text + "}\n";
}

// Runs the loop until `done` or `limit_s`; returns the elapsed time or -1.
double RunUntil(EventLoop* loop, const std::function<bool()>& done, double limit_s) {
  const double start = Now();
  while (!done()) {
    if (Now() - start > limit_s) return -1;
    loop->RunOnce(0.05);
  }
  return Now() - start;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? -1 : v[v.size() / 2];
}

double ProcessCpuSeconds(int pid) {
  ProcInfo info;
  if (!ReadProcInfo(pid, &info)) return -1;
  return static_cast<double>(info.ticks) / static_cast<double>(ClockTicksPerSecond());
}

}  // namespace

int main() {
  Scratch scratch;
  const Key key = LoadKeyFile(scratch.key());
  const ProcmanOptions options;
  const std::string deputy_id = "bench" + std::to_string(getpid());
  const int marker = 600000 + (getpid() % 1000) * 100;
  Child deputy({BinDir() + "/sarmap-procman-deputy", "--id", deputy_id, "--key", scratch.key(),
                "--log-level", "warn"},
               scratch.dir() + "/deputy.log");

  lcm::LCM lcm(sarmap::common::DefaultLcmUrl());
  if (!lcm.good()) {
    fprintf(stderr, "LCM init failed\n");
    return 1;
  }
  EventLoop loop(&lcm);

  // --- 1. start -> 10 running ---------------------------------------------------------------
  {
    const Config config = ParseConfig(MakeConfig(deputy_id, 10, marker), "bench10.pmd");
    Sheriff sheriff(&lcm, options, config, &key, "bench-sheriff");
    loop.Add(&sheriff);
    if (RunUntil(
            &loop, [&] { return sheriff.AllDeputiesHeard(); }, 10) < 0) {
      fprintf(stderr, "deputy not heard: %s\n", deputy.Log().c_str());
      return 1;
    }
    const Target all;
    std::vector<double> warm;
    for (int rep = 0; rep < 7; ++rep) {
      sheriff.Apply(Sheriff::Verb::kStart, all);
      const double t = RunUntil(
          &loop, [&] { return sheriff.Reached(all, "running", Now(), nullptr); }, 20);
      warm.push_back(t);
      sheriff.Apply(Sheriff::Verb::kStop, all);
      RunUntil(
          &loop, [&] { return sheriff.Reached(all, "stopped", Now(), nullptr); }, 20);
    }
    printf(
        "FIGURE start -> all 10 commands running (sheriff already connected): median %.1f ms, min "
        "%.1f ms, "
        "max %.1f ms over %zu runs\n",
        1e3 * Median(warm), 1e3 * *std::min_element(warm.begin(), warm.end()),
        1e3 * *std::max_element(warm.begin(), warm.end()), warm.size());
    // Leave the deputy as the sheriff left it; the CLI runs below are separate sheriffs.
    RunUntil(
        &loop, [] { return false; }, 0.2);
  }
  {
    // The Sheriff above is gone; its orders stay in force (all stopped). End to end via the CLI.
    const std::string pmd = scratch.Write("bench10.pmd", MakeConfig(deputy_id, 10, marker));
    std::vector<double> cli;
    for (int rep = 0; rep < 3; ++rep) {
      const double t0 = SteadyNow();
      const CliResult r =
          Run({BinDir() + "/sarmap-procman", pmd, "--key", scratch.key(), "start", "everything"},
              scratch.dir() + "/cli.log");
      const double t = SteadyNow() - t0;
      if (r.exit_code != 0) fprintf(stderr, "CLI start failed: %s\n", r.output.c_str());
      cli.push_back(t);
      Run({BinDir() + "/sarmap-procman", pmd, "--key", scratch.key(), "stop", "everything"},
          scratch.dir() + "/cli.log");
    }
    printf(
        "FIGURE `sarmap-procman CONFIG start everything` until all 10 running, end to end (process "
        "start, "
        "hearing the deputy's 1 Hz PM_INFO, orders, exec): median %.0f ms, min %.0f, max %.0f over "
        "%zu runs\n",
        1e3 * Median(cli), 1e3 * *std::min_element(cli.begin(), cli.end()),
        1e3 * *std::max_element(cli.begin(), cli.end()), cli.size());
  }

  // --- 2. idle deputy with 20 commands ---------------------------------------------------------
  {
    const Config config = ParseConfig(MakeConfig(deputy_id, 20, marker + 50), "bench20.pmd");
    Sheriff sheriff(&lcm, options, config, &key, "bench-sheriff");
    EventLoop loop20(&lcm);
    loop20.Add(&sheriff);
    RunUntil(
        &loop20, [&] { return sheriff.AllDeputiesHeard(); }, 10);
    sheriff.Apply(Sheriff::Verb::kStart, Target{});
    if (RunUntil(
            &loop20, [&] { return sheriff.Reached(Target{}, "running", Now(), nullptr); }, 20) <
        0) {
      fprintf(stderr, "20 commands did not all start\n");
      return 1;
    }
    RunUntil(
        &loop20, [] { return false; }, 2.0);  // settle
    const double window_s = 10.0;
    const double cpu0 = ProcessCpuSeconds(deputy.pid());
    rusage before;
    getrusage(RUSAGE_SELF, &before);
    const double t0 = Now();
    RunUntil(
        &loop20, [] { return false; }, window_s);
    const double elapsed = Now() - t0;
    const double cpu1 = ProcessCpuSeconds(deputy.pid());
    rusage after;
    getrusage(RUSAGE_SELF, &after);
    auto seconds = [](const timeval& tv) { return tv.tv_sec + tv.tv_usec * 1e-6; };
    const double self_s = seconds(after.ru_utime) + seconds(after.ru_stime) -
                          seconds(before.ru_utime) - seconds(before.ru_stime);
    printf(
        "FIGURE idle deputy CPU with 20 commands running: %.3f %% of one core (%.3f s CPU in %.1f "
        "s; "
        "1 Hz PM_INFO with /proc sampling of all 20 trees, 1 Hz orders from the sheriff)\n",
        100.0 * (cpu1 - cpu0) / elapsed, cpu1 - cpu0, elapsed);
    printf("FIGURE live sheriff CPU meanwhile (this process): %.3f %% of one core\n",
           100.0 * self_s / elapsed);
    sheriff.Apply(Sheriff::Verb::kStop, Target{});
    RunUntil(
        &loop20, [&] { return sheriff.Reached(Target{}, "stopped", Now(), nullptr); }, 20);
  }
  deputy.Signal(SIGTERM);
  deputy.Wait(10);
  return 0;
}
