#pragma once
// Helpers for the multi-process procman tests and the benchmark: child processes, one-shot
// CLI runs, and an LCM watcher of PM_INFO / PM_ORDERS. Header-only, test code only.

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/node.h"
#include "procman/process_table.h"
#include "sarmap/pm_info_t.hpp"
#include "sarmap/pm_orders_t.hpp"

namespace sarmap {
namespace procman {
namespace testing {

inline double SteadyNow() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

inline std::string BinDir() { return SARMAP_BIN_DIR; }

// A scratch directory with a key file (0600); removed at the end.
class Scratch {
 public:
  Scratch() {
    char tmpl[] = "/tmp/procman_test_XXXXXX";
    if (!mkdtemp(tmpl)) throw std::runtime_error("mkdtemp failed");
    dir_ = tmpl;
    key_ = dir_ + "/procman.key";
    WriteKey(key_, 1);
  }
  ~Scratch() {
    const std::string cmd = "rm -rf '" + dir_ + "'";
    if (system(cmd.c_str()) != 0) {
    }
  }
  static void WriteKey(const std::string& path, int seed) {
    std::ofstream out(path, std::ios::binary);
    for (int i = 0; i < 32; ++i) out.put(static_cast<char>((seed * 31 + i * 7) & 0xff));
    out.close();
    chmod(path.c_str(), 0600);
  }
  std::string Write(const std::string& name, const std::string& text) const {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }
  const std::string& dir() const { return dir_; }
  const std::string& key() const { return key_; }

 private:
  std::string dir_, key_;
};

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A background process with its stdout+stderr in a log file.
class Child {
 public:
  Child(std::vector<std::string> argv, std::string log_path) : log_(std::move(log_path)) {
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      const int in = open("/dev/null", O_RDONLY);
      dup2(in, 0);
      execv(args[0], args.data());
      _exit(127);
    }
  }
  // A clean stop first (a deputy stops its commands), then SIGKILL.
  ~Child() {
    if (pid_ > 0) {
      Signal(SIGTERM);
      if (Wait(10) == -1) {
        Signal(SIGKILL);
        Wait();
      }
    }
  }
  void Signal(int sig) {
    if (pid_ > 0) kill(pid_, sig);
  }
  // Returns the exit status (as from waitpid), or -1 when it did not end within limit_s.
  int Wait(double limit_s = 30) {
    const double end = SteadyNow() + limit_s;
    while (pid_ > 0) {
      int status = 0;
      const pid_t r = waitpid(pid_, &status, WNOHANG);
      if (r == pid_) {
        pid_ = -1;
        return status;
      }
      if (SteadyNow() > end) return -1;
      usleep(10000);
    }
    return -1;
  }
  int pid() const { return pid_; }
  std::string Log() const { return ReadFile(log_); }

 private:
  pid_t pid_ = -1;
  std::string log_;
};

struct CliResult {
  int exit_code = -1;
  std::string output;
};

// Runs a program to completion, capturing stdout+stderr.
inline CliResult Run(const std::vector<std::string>& argv, const std::string& log_path) {
  unlink(log_path.c_str());
  Child c(argv, log_path);
  const int status = c.Wait(120);
  CliResult r;
  r.exit_code = status >= 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.output = ReadFile(log_path);
  return r;
}

// Watches PM_INFO (latest per deputy) and PM_ORDERS (raw copies, for replay tests).
class Watcher {
 public:
  Watcher() : lcm_(common::DefaultLcmUrl()) {
    if (!lcm_.good()) throw std::runtime_error("LCM init failed");
    lcm_.subscribe("^PM_INFO$", &Watcher::OnInfo, this);
    lcm_.subscribe("^PM_ORDERS$", &Watcher::OnOrders, this);
  }
  lcm::LCM& lcm() { return lcm_; }

  // Handles messages until `done` or `limit_s` passed; false on the limit.
  bool WaitFor(const std::function<bool()>& done, double limit_s = 15.0) {
    const double end = SteadyNow() + limit_s;
    while (!done()) {
      const double left = end - SteadyNow();
      if (left <= 0) return false;
      lcm_.handleTimeout(static_cast<int>(std::min(left, 0.1) * 1000) + 1);
    }
    return true;
  }
  void Spin(double seconds) {
    WaitFor([] { return false; }, seconds);
  }

  bool Heard(const std::string& deputy) const { return info_.count(deputy) > 0; }
  // Forgets what a deputy reported (before starting it again).
  void Forget(const std::string& deputy) {
    info_.erase(deputy);
    heard_s_.erase(deputy);
  }
  const sarmap::pm_info_t& Info(const std::string& deputy) const { return info_.at(deputy); }
  // The deputy's session clock now (microseconds), from its last report: what the counter of
  // an order to it must be close to.
  int64_t DeputyClockUs(const std::string& deputy) const {
    return Info(deputy).session_clock_us +
           static_cast<int64_t>((SteadyNow() - heard_s_.at(deputy)) * 1e6);
  }
  double LastHeard(const std::string& deputy) const {
    auto it = heard_s_.find(deputy);
    return it == heard_s_.end() ? -1e9 : it->second;
  }
  // Status of a command as last reported; nullptr if not reported.
  const sarmap::pm_command_status_t* Command(const std::string& deputy,
                                             const std::string& id) const {
    auto it = info_.find(deputy);
    if (it == info_.end()) return nullptr;
    for (const auto& c : it->second.commands) {
      if (c.command_id == id) return &c;
    }
    return nullptr;
  }
  bool IsRunning(const std::string& deputy, const std::string& id) const {
    const auto* c = Command(deputy, id);
    return c && c->state == sarmap::pm_command_status_t::STATE_RUNNING && c->pid > 0;
  }
  // Reported by the deputy as stopped or failed (a command it does not know is neither).
  bool IsStopped(const std::string& deputy, const std::string& id) const {
    const auto* c = Command(deputy, id);
    return c && (c->state == sarmap::pm_command_status_t::STATE_STOPPED ||
                 c->state == sarmap::pm_command_status_t::STATE_FAILED);
  }
  int Pid(const std::string& deputy, const std::string& id) const {
    const auto* c = Command(deputy, id);
    return c ? c->pid : 0;
  }
  // Every PM_INFO received for a deputy, in order (for timing from the deputy's own stamps).
  const std::vector<sarmap::pm_info_t>& History(const std::string& deputy) {
    return history_[deputy];
  }
  const std::vector<std::vector<uint8_t>>& RawOrders() const { return raw_orders_; }
  const std::vector<sarmap::pm_orders_t>& Orders() const { return orders_; }

 private:
  void OnInfo(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    sarmap::pm_info_t info;
    if (info.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
    heard_s_[info.deputy_id] = SteadyNow();
    history_[info.deputy_id].push_back(info);
    info_[info.deputy_id] = std::move(info);
  }
  void OnOrders(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    raw_orders_.emplace_back(p, p + rbuf->data_size);
    sarmap::pm_orders_t o;
    if (o.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0) orders_.push_back(o);
  }

  lcm::LCM lcm_;
  std::map<std::string, sarmap::pm_info_t> info_;
  std::map<std::string, double> heard_s_;
  std::map<std::string, std::vector<sarmap::pm_info_t>> history_;
  std::vector<std::vector<uint8_t>> raw_orders_;
  std::vector<sarmap::pm_orders_t> orders_;
};

inline std::string NetNamespaceOf(const std::string& pid) {
  char buf[128] = {0};
  const ssize_t n = readlink(("/proc/" + pid + "/ns/net").c_str(), buf, sizeof(buf) - 1);
  return n > 0 ? std::string(buf, static_cast<size_t>(n)) : "";
}

// Live (non-zombie) processes of our network namespace (parallel test runs each have their
// own) whose full command line is exactly `cmdline` (words joined by spaces).
inline std::vector<int> ProcessesWithCmdline(const std::string& cmdline) {
  std::vector<int> out;
  const std::string our_net = NetNamespaceOf("self");
  const ProcessTable table = ProcessTable::Snapshot();
  for (const auto& [pid, info] : table.processes()) {
    if (info.state == 'Z' || NetNamespaceOf(std::to_string(pid)) != our_net) continue;
    std::string text = ReadFile("/proc/" + std::to_string(pid) + "/cmdline");
    if (text.empty()) continue;
    if (text.back() == '\0') text.pop_back();
    for (auto& ch : text) {
      if (ch == '\0') ch = ' ';
    }
    if (text == cmdline) out.push_back(pid);
  }
  return out;
}

inline bool Alive(int pid) {
  ProcInfo info;
  return pid > 0 && ReadProcInfo(pid, &info) && info.state != 'Z';
}

// The processes `pids` name now (pid and start time), to ask later whether those very processes
// still run: with pid_max 32768 a busy machine hands a freed pid to another process within
// seconds.
inline std::vector<ProcInfo> Snapshot(const std::vector<int>& pids) {
  std::vector<ProcInfo> out;
  for (int pid : pids) {
    ProcInfo info;
    if (pid > 0 && ReadProcInfo(pid, &info)) out.push_back(info);
  }
  return out;
}

// The process `then` describes still runs (the same pid and start time, not a zombie).
inline bool StillRunning(const ProcInfo& then) { return Running(then.pid, then.start_time); }

}  // namespace testing
}  // namespace procman
}  // namespace sarmap
