#pragma once
// A snapshot of /proc: every process with its parent, process group, CPU ticks and resident
// memory, so the supervisor can count a command's children and find every descendant to
// stop (also ones that left the process group).

#include <cstdint>
#include <map>
#include <vector>

namespace sarmap {
namespace procman {

struct ProcInfo {
  int pid = 0;
  int ppid = 0;
  int pgid = 0;
  char state = '?';
  uint64_t ticks = 0;        // utime + stime of the process itself
  uint64_t child_ticks = 0;  // cutime + cstime: children it has reaped
  uint64_t start_time = 0;   // since boot, in clock ticks: tells a reused pid apart
  int64_t rss_bytes = 0;
};

// Reads /proc/<pid>/stat; false when the process is gone or unreadable.
bool ReadProcInfo(int pid, ProcInfo* info);

// The process with this pid and start time still runs (not a zombie); a pid reused by another
// process is not it.
bool Running(int pid, uint64_t start_time);

class ProcessTable {
 public:
  // Reads all of /proc.
  static ProcessTable Snapshot();

  const std::map<int, ProcInfo>& processes() const { return processes_; }
  // `root` and everything below it (by parent links), plus every member of process group
  // `pgid` (> 0) and their descendants. Zombies are left out.
  std::vector<int> Tree(int root, int pgid) const;

 private:
  std::map<int, ProcInfo> processes_;
  std::map<int, std::vector<int>> children_;
};

// Whole-machine CPU load (0..1 since the previous call) and memory.
class MachineUsage {
 public:
  void Update();
  double cpu_load() const { return cpu_load_; }
  int64_t mem_total_bytes() const { return mem_total_; }
  int64_t mem_free_bytes() const { return mem_free_; }

 private:
  uint64_t prev_busy_ = 0, prev_total_ = 0;
  double cpu_load_ = 0;
  int64_t mem_total_ = 0, mem_free_ = 0;
};

int64_t ClockTicksPerSecond();

}  // namespace procman
}  // namespace sarmap
