#pragma once
// Process supervision for one deputy: brings the actual state of its commands to the desired
// state it was ordered, and reports it. No LCM here; the deputy node feeds orders in and
// publishes Status() and TakeOutput().
//
// - A command runs without a shell (see exec_line.h) unless use_shell, in its own process
//   group, stdin from /dev/null, stdout+stderr into one pipe that the supervisor reads.
// - Stop: the configured signal to the whole group and to every descendant seen (also ones
//   that left the group), then SIGKILL to all of them after stop_time_allowed. A stop ends
//   only when no descendant is left. The owning process should be a child subreaper
//   (BecomeSubreaper()) so that orphaned grandchildren come back to it to be reaped.
// - A command that exits on its own leaves nothing behind: what is left of its tree is killed.
// - auto_respawn: restarted after a back-off of base * 2^k (k = quick crashes in a row, a run
//   longer than `stable_run_s` resets it), capped at max.
// - desired_runid versions the desired state of a command: the sheriff bumps it on every
//   change (start, stop, restart). A new run id while running means restart; a stopped
//   command takes the run id of the stop as its actual_runid.
// - CPU (percent of one core) and RSS include all descendants, from /proc (UpdateUsage()).

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace sarmap {
namespace procman {

enum class CommandState : int8_t {
  kStopped = 0,
  kStarting = 1,
  kRunning = 2,
  kStopping = 3,
  kFailed = 4,
  kRespawnWait = 5,
};
const char* ToString(CommandState state);

// The environment a command starts with (NAME -> value); `${NAME}` in an exec line is looked
// up in it too.
using Environment = std::map<std::string, std::string>;

// This process's environment, to be passed on to the commands, with `bin_dir` (if not empty)
// put first on PATH so that commands find the programs installed beside the launcher.
Environment InheritedEnvironment(const std::string& bin_dir = "");
// The directory of this process's executable ("" if /proc does not tell).
std::string OwnDirectory();

struct CommandSpec {
  std::string id;
  std::string group;
  std::string exec;
  bool use_shell = false;
  bool auto_respawn = false;
  int stop_signal = 2;
  double stop_time_allowed_s = 7.0;
  bool desired_running = false;
  int32_t desired_runid = 0;
};

struct CommandStatus {
  std::string id;
  std::string group;
  std::string exec;
  CommandState state = CommandState::kStopped;
  int pid = 0;
  int exit_code = 0;
  int restart_count = 0;
  int32_t actual_runid = 0;
  double cpu_percent = 0;
  int64_t rss_bytes = 0;
  bool auto_respawn = false;
};

struct RespawnPolicy {
  double base_s = 0.1;
  double max_s = 10.0;
  double stable_run_s = 5.0;
  // Delay before respawn number `quick_crashes` (0 = first crash after a stable run).
  double Delay(int quick_crashes) const;
};

// Makes this process the reaper of its orphaned descendants (Linux PR_SET_CHILD_SUBREAPER).
bool BecomeSubreaper();

// Starts this process's group guardian: a small child process, in a process group of its own,
// that every Supervisor here tells which command process groups are alive. When this process
// ends in any way (SIGKILL, OOM, a crash), the guardian kills those groups with SIGKILL: the
// commands die with their deputy (PR_SET_PDEATHSIG) and so do the processes they forked
// (a shell's background jobs), which stay in the command's group. False (errno set) when it
// cannot be started; the commands themselves still die with the deputy.
bool StartGroupGuardian();

class Supervisor {
 public:
  explicit Supervisor(RespawnPolicy respawn = RespawnPolicy(), size_t max_buffered_output = 65536,
                      Environment environment = InheritedEnvironment());
  // Kills everything still running (SIGKILL, no grace): call Shutdown() first for a clean stop.
  ~Supervisor();
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;

  // The complete desired state: commands not listed are stopped and then forgotten.
  void SetDesired(const std::vector<CommandSpec>& specs);
  // Stops every command (for exit); AllStopped() tells when done.
  void Shutdown();
  bool AllStopped() const;

  // Reaps children, reads output, escalates stops, starts and respawns. Call it whenever a
  // child may have exited (SIGCHLD), output is readable, at NextWakeup(), and after
  // SetDesired(). Returns true when any command's state, pid or counters changed.
  bool Step(double now_s);
  // Steady-clock time at which Step() must run again (stop deadlines, respawns); +inf if none.
  double NextWakeup() const;
  // Output pipes to poll for reading.
  std::vector<int> OutputFds() const;

  // Samples CPU and RSS of every running command (and its descendants) from /proc.
  void UpdateUsage(double now_s);

  std::vector<CommandStatus> Status() const;
  // The desired state last given for a command; nullptr if unknown.
  const CommandSpec* FindSpec(const std::string& id) const;
  // Captured output per command since the last call, at most `max_bytes` each (the rest
  // stays buffered). Commands without new output are left out.
  std::vector<std::pair<std::string, std::string>> TakeOutput(size_t max_bytes);

 private:
  struct Managed;
  void Start(Managed* m, double now_s);
  void BeginStop(Managed* m, double now_s);
  void SignalTree(Managed* m, int sig);
  bool TreeAlive(Managed* m);
  void OnExit(Managed* m, int wait_status, double now_s);
  bool ReapAll(double now_s);
  void ReadOutput(Managed* m);
  void AppendOutput(Managed* m, const std::string& text);
  // Sets m->pgid (0: none), telling the group guardian.
  static void SetGroup(Managed* m, int pgid);

  RespawnPolicy respawn_;
  size_t max_buffered_output_;
  Environment environment_;
  bool shutting_down_ = false;
  double last_step_s_ = 0;
  std::vector<std::unique_ptr<Managed>> commands_;  // in the order they were first ordered
};

}  // namespace procman
}  // namespace sarmap
