#include "procman/process_table.h"

#include <dirent.h>
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <string>

namespace sarmap {
namespace procman {
namespace {

// Reads a small /proc file into buf; returns its length or -1.
ssize_t ReadSmallFile(const char* path, char* buf, size_t size) {
  const int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  ssize_t total = 0;
  while (static_cast<size_t>(total) < size - 1) {
    const ssize_t n = read(fd, buf + total, size - 1 - static_cast<size_t>(total));
    if (n <= 0) break;
    total += n;
  }
  close(fd);
  buf[total] = '\0';
  return total;
}

}  // namespace

int64_t ClockTicksPerSecond() {
  static const int64_t hz = sysconf(_SC_CLK_TCK) > 0 ? sysconf(_SC_CLK_TCK) : 100;
  return hz;
}

bool ReadProcInfo(int pid, ProcInfo* info) {
  char path[64];
  snprintf(path, sizeof(path), "/proc/%d/stat", pid);
  char buf[1024];
  if (ReadSmallFile(path, buf, sizeof(buf)) <= 0) return false;
  // The command name is in parentheses and may contain anything; fields follow the last ')'.
  const char* close = strrchr(buf, ')');
  if (!close || close[1] == '\0') return false;
  const char* p = close + 2;
  info->pid = pid;
  info->state = *p;
  // Fields 4.. after the state (field 3), numbered as in proc(5).
  unsigned long long field[25] = {0};
  char* cursor = const_cast<char*>(p + 1);
  for (int f = 4; f <= 24; ++f) {
    char* end = nullptr;
    field[f] = strtoull(cursor, &end, 10);
    if (end == cursor) return false;
    cursor = end;
  }
  static const long page = sysconf(_SC_PAGESIZE);
  info->ppid = static_cast<int>(field[4]);
  info->pgid = static_cast<int>(field[5]);
  info->ticks = field[14] + field[15];
  info->child_ticks = field[16] + field[17];
  info->start_time = field[22];
  info->rss_bytes = static_cast<int64_t>(field[24]) * page;
  return true;
}

bool Running(int pid, uint64_t start_time) {
  ProcInfo info;
  return ReadProcInfo(pid, &info) && info.start_time == start_time && info.state != 'Z';
}

ProcessTable ProcessTable::Snapshot() {
  ProcessTable table;
  DIR* dir = opendir("/proc");
  if (!dir) return table;
  while (dirent* entry = readdir(dir)) {
    const char* name = entry->d_name;
    if (name[0] < '0' || name[0] > '9') continue;
    ProcInfo info;
    if (ReadProcInfo(atoi(name), &info)) {
      table.children_[info.ppid].push_back(info.pid);
      table.processes_[info.pid] = info;
    }
  }
  closedir(dir);
  return table;
}

std::vector<int> ProcessTable::Tree(int root, int pgid) const {
  std::vector<int> out;
  std::set<int> seen;
  std::vector<int> todo;
  if (processes_.count(root)) todo.push_back(root);
  if (pgid > 0) {
    for (const auto& [pid, info] : processes_) {
      if (info.pgid == pgid) todo.push_back(pid);
    }
  }
  while (!todo.empty()) {
    const int pid = todo.back();
    todo.pop_back();
    if (!seen.insert(pid).second) continue;
    auto it = processes_.find(pid);
    if (it == processes_.end()) continue;
    if (it->second.state != 'Z') out.push_back(pid);
    auto kids = children_.find(pid);
    if (kids != children_.end()) {
      for (int k : kids->second) todo.push_back(k);
    }
  }
  return out;
}

void MachineUsage::Update() {
  char buf[4096];
  if (ReadSmallFile("/proc/stat", buf, sizeof(buf)) > 0 && strncmp(buf, "cpu ", 4) == 0) {
    unsigned long long v[10] = {0};
    sscanf(buf + 4, "%llu %llu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3],
           &v[4], &v[5], &v[6], &v[7], &v[8], &v[9]);
    uint64_t total = 0;
    for (int i = 0; i < 8; ++i) total += v[i];  // guest time is already in user
    const uint64_t idle = v[3] + v[4];
    const uint64_t busy = total - idle;
    if (prev_total_ > 0 && total > prev_total_) {
      cpu_load_ = static_cast<double>(busy - prev_busy_) / static_cast<double>(total - prev_total_);
    }
    prev_total_ = total;
    prev_busy_ = busy;
  }
  if (ReadSmallFile("/proc/meminfo", buf, sizeof(buf)) > 0) {
    const char* total = strstr(buf, "MemTotal:");
    const char* avail = strstr(buf, "MemAvailable:");
    if (total) mem_total_ = atoll(total + 9) * 1024;
    if (avail) mem_free_ = atoll(avail + 13) * 1024;
  }
}

}  // namespace procman
}  // namespace sarmap
