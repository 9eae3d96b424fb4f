#include "procman/supervisor.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "procman/exec_line.h"
#include "procman/process_table.h"

extern char** environ;

namespace sarmap {
namespace procman {

const char* ToString(CommandState state) {
  switch (state) {
    case CommandState::kStopped:
      return "stopped";
    case CommandState::kStarting:
      return "starting";
    case CommandState::kRunning:
      return "running";
    case CommandState::kStopping:
      return "stopping";
    case CommandState::kFailed:
      return "failed";
    case CommandState::kRespawnWait:
      return "respawn-wait";
  }
  return "?";
}

double RespawnPolicy::Delay(int quick_crashes) const {
  const double d = base_s * std::pow(2.0, std::min(quick_crashes, 30));
  return std::min(d, max_s);
}

bool BecomeSubreaper() { return prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0; }

namespace {

// PATH for commands when the environment has none.
constexpr const char* kDefaultPath = "/usr/local/bin:/usr/bin:/bin";

// This process's end of the socket to its group guardian (-1: none). Records of 5 bytes: '+' or
// '-', then the process group id (native int32).
int g_guardian_fd = -1;

[[noreturn]] void RunGroupGuardian(int fd) {
  // Only async-signal-safe calls: the parent may have had threads when it forked.
  for (int s : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE}) signal(s, SIG_IGN);
  setpgid(0, 0);  // signals to the deputy's group do not reach it
  prctl(PR_SET_NAME, "procman-guard", 0, 0, 0);
  constexpr int kMaxGroups = 4096;
  static int groups[kMaxGroups];
  int num_groups = 0;
  unsigned char record[5];
  size_t have = 0;
  while (true) {
    const ssize_t n = read(fd, record + have, sizeof(record) - have);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // the deputy is gone (or closed its end)
    have += static_cast<size_t>(n);
    if (have < sizeof(record)) continue;
    have = 0;
    int pgid;
    memcpy(&pgid, record + 1, sizeof(pgid));
    if (pgid <= 0) continue;
    if (record[0] == '+' && num_groups < kMaxGroups) {
      groups[num_groups++] = pgid;
    } else if (record[0] == '-') {
      for (int i = 0; i < num_groups; ++i) {
        if (groups[i] == pgid) {
          groups[i] = groups[--num_groups];
          break;
        }
      }
    }
  }
  for (int i = 0; i < num_groups; ++i) kill(-groups[i], SIGKILL);
  _exit(0);
}

void TellGuardian(char op, int pgid) {
  if (g_guardian_fd < 0 || pgid <= 0) return;
  unsigned char record[5];
  record[0] = static_cast<unsigned char>(op);
  memcpy(record + 1, &pgid, sizeof(pgid));
  // One record is far below a socket buffer: written whole or not at all (a guardian that died).
  if (send(g_guardian_fd, record, sizeof(record), MSG_NOSIGNAL | MSG_DONTWAIT) != sizeof(record)) {
    close(g_guardian_fd);
    g_guardian_fd = -1;
  }
}

}  // namespace

bool StartGroupGuardian() {
  if (g_guardian_fd >= 0) return true;
  int sv[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) return false;
  const pid_t pid = fork();
  if (pid < 0) {
    close(sv[0]);
    close(sv[1]);
    return false;
  }
  if (pid == 0) {
    // Keep nothing of the deputy's but the socket (no pipe or LCM socket held open).
    const long max_fd = std::min(sysconf(_SC_OPEN_MAX), 65536L);
    for (int fd = 0; fd < max_fd; ++fd) {
      if (fd != sv[1]) close(fd);
    }
    RunGroupGuardian(sv[1]);
  }
  close(sv[1]);
  g_guardian_fd = sv[0];
  return true;
}

struct Supervisor::Managed {
  CommandSpec spec;
  bool removed = false;
  CommandState state = CommandState::kStopped;
  int pid = 0;   // the command's own process while it lives
  int pgid = 0;  // its process group, kept until nothing of the run is left
  int exit_code = 0;
  int restart_count = 0;
  int32_t actual_runid = 0;
  bool exited_on_its_own = false;  // then it is not started again for the same runid
  int out_fd = -1;
  std::string output;
  size_t output_dropped = 0;
  double started_s = 0;
  double stop_deadline_s = 0;
  bool killed = false;
  double respawn_at_s = 0;
  int quick_crashes = 0;
  std::vector<std::pair<int, uint64_t>> tree;  // descendants seen: pid, start time
  double cpu_percent = 0;
  int64_t rss_bytes = 0;
  uint64_t prev_ticks = 0;
  double prev_ticks_s = -1;
};

void Supervisor::SetGroup(Managed* m, int pgid) {
  if (m->pgid == pgid) return;
  TellGuardian('-', m->pgid);
  m->pgid = pgid;
  TellGuardian('+', pgid);
}

namespace {

// Several deputies in one process (--lone-ranger) share waitpid(-1): what one Supervisor
// reaps for another's command is kept here until its owner claims it. (Single-threaded, like
// the event loop.)
struct ReapBoard {
  std::set<pid_t> commands;       // command pids of every Supervisor of this process
  std::map<pid_t, int> statuses;  // reaped by another Supervisor, not yet claimed
};
ReapBoard& Board() {
  static ReapBoard board;
  return board;
}

}  // namespace

Environment InheritedEnvironment(const std::string& bin_dir) {
  Environment environment;
  for (char** e = environ; e && *e; ++e) {
    const std::string entry = *e;
    const size_t equals = entry.find('=');
    if (equals == std::string::npos || equals == 0) continue;
    environment.emplace(entry.substr(0, equals), entry.substr(equals + 1));
  }
  if (!bin_dir.empty()) {
    const auto path = environment.find("PATH");
    environment["PATH"] =
        bin_dir + ":" + (path != environment.end() ? path->second : kDefaultPath);
  }
  return environment;
}

std::string OwnDirectory() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) return "";
  self[n] = '\0';
  const std::string path(self);
  return path.substr(0, path.rfind('/'));
}

Supervisor::Supervisor(RespawnPolicy respawn, size_t max_buffered_output, Environment environment)
    : respawn_(respawn),
      max_buffered_output_(max_buffered_output),
      environment_(std::move(environment)) {}

Supervisor::~Supervisor() {
  for (auto& m : commands_) {
    if (m->pid > 0 || m->pgid > 0) SignalTree(m.get(), SIGKILL);
    if (m->pid > 0) {
      int status = 0;
      while (waitpid(m->pid, &status, 0) < 0 && errno == EINTR) {
      }
      Board().commands.erase(m->pid);
      Board().statuses.erase(m->pid);
    }
    if (m->out_fd >= 0) close(m->out_fd);
  }
}

void Supervisor::SetDesired(const std::vector<CommandSpec>& specs) {
  for (auto& m : commands_) m->removed = true;
  for (const auto& spec : specs) {
    Managed* found = nullptr;
    for (auto& m : commands_) {
      if (m->spec.id == spec.id) found = m.get();
    }
    if (!found) {
      commands_.push_back(std::make_unique<Managed>());
      found = commands_.back().get();
    }
    // A changed exec line applies from the next start.
    found->spec = spec;
    found->removed = false;
  }
}

void Supervisor::Shutdown() { shutting_down_ = true; }

bool Supervisor::AllStopped() const {
  for (const auto& m : commands_) {
    if (m->pid > 0 || m->state == CommandState::kStopping || m->state == CommandState::kRunning ||
        m->state == CommandState::kStarting) {
      return false;
    }
  }
  return true;
}

void Supervisor::AppendOutput(Managed* m, const std::string& text) {
  m->output += text;
  if (m->output.size() > max_buffered_output_) {
    const size_t drop = m->output.size() - max_buffered_output_;
    m->output.erase(0, drop);
    m->output_dropped += drop;
  }
}

void Supervisor::ReadOutput(Managed* m) {
  if (m->out_fd < 0) return;
  char buf[8192];
  while (true) {
    const ssize_t n = read(m->out_fd, buf, sizeof(buf));
    if (n > 0) {
      AppendOutput(m, std::string(buf, static_cast<size_t>(n)));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK)) {
      close(m->out_fd);  // every writer (the command and its descendants) is gone
      m->out_fd = -1;
    }
    return;
  }
}

void Supervisor::SignalTree(Managed* m, int sig) {
  // Walk the tree before signalling: once a parent dies its children are re-parented (to us,
  // the subreaper) and the parent links that lead to them are gone. This also finds
  // descendants that left the group (setsid, daemons).
  const ProcessTable table = ProcessTable::Snapshot();
  for (int pid : table.Tree(m->pid, m->pgid)) {
    const uint64_t start = table.processes().at(pid).start_time;
    bool known = false;
    for (const auto& [p, st] : m->tree) known = known || (p == pid && st == start);
    if (!known) m->tree.emplace_back(pid, start);
  }
  if (m->pgid > 0) kill(-m->pgid, sig);
  for (const auto& [pid, start] : m->tree)
    if (Running(pid, start)) kill(pid, sig);
}

bool Supervisor::TreeAlive(Managed* m) {
  if (m->pgid > 0 && kill(-m->pgid, 0) == 0) return true;
  for (const auto& [pid, start] : m->tree)
    if (Running(pid, start)) return true;
  return false;
}

void Supervisor::Start(Managed* m, double now_s) {
  m->exited_on_its_own = false;
  m->killed = false;
  m->tree.clear();
  m->actual_runid = m->spec.desired_runid;
  m->prev_ticks_s = -1;
  m->cpu_percent = 0;
  m->rss_bytes = 0;
  if (m->out_fd >= 0) {  // what an earlier run left in the pipe
    ReadOutput(m);
    if (m->out_fd >= 0) close(m->out_fd);
    m->out_fd = -1;
  }
  m->started_s = now_s;

  auto fail = [&](const std::string& why) {
    AppendOutput(m, "[procman] cannot start: " + why + "\n");
    m->pid = 0;
    SetGroup(m, 0);
    m->state = CommandState::kRunning;  // so that OnExit treats it as a crash
    OnExit(m, -1, now_s);
  };

  ExecPlan plan;
  if (m->spec.use_shell) {
    plan.argv = {"/bin/sh", "-c", m->spec.exec};
  } else {
    try {
      plan = PlanExec(m->spec.exec, [this](const std::string& name) -> const char* {
        const auto value = environment_.find(name);
        return value == environment_.end() ? nullptr : value->second.c_str();
      });
    } catch (const std::invalid_argument& e) {
      fail(e.what());
      return;
    }
  }
  // The command's environment: ours plus its NAME=VALUE prefixes.
  Environment environment = environment_;
  for (const auto& [name, value] : plan.env) environment[name] = value;
  std::vector<std::string> env_strings;
  for (const auto& [name, value] : environment) env_strings.push_back(name + "=" + value);
  const auto path = environment.find("PATH");
  const std::string path_list = path != environment.end() ? path->second : kDefaultPath;
  const std::string program = FindExecutable(plan.argv[0], path_list);
  if (program.empty()) {
    fail("'" + plan.argv[0] + "' not found (or not executable) in PATH");
    return;
  }
  std::vector<char*> argv, envp;
  for (auto& a : plan.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (auto& e : env_strings) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);

  int out_pipe[2], err_pipe[2];
  if (pipe2(out_pipe, O_CLOEXEC) != 0) {
    fail(std::string("pipe: ") + strerror(errno));
    return;
  }
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    close(out_pipe[0]);
    close(out_pipe[1]);
    fail(std::string("pipe: ") + strerror(errno));
    return;
  }
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    for (int fd : {out_pipe[0], out_pipe[1], err_pipe[0], err_pipe[1]}) close(fd);
    fail(std::string("fork: ") + strerror(errno));
    return;
  }
  if (pid == 0) {
    // Child: only async-signal-safe calls from here to exec.
    setpgid(0, 0);
    // Dies with its deputy: a deputy that is killed (SIGKILL, OOM) leaves no orphan running
    // unsupervised, and a restarted deputy never finds a second copy of its commands.
    prctl(PR_SET_PDEATHSIG, SIGKILL, 0, 0, 0);
    if (getppid() != parent) _exit(127);  // the deputy died before prctl took effect
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) dup2(devnull, 0);
    dup2(out_pipe[1], 1);
    dup2(out_pipe[1], 2);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int s = 1; s < NSIG; ++s) signal(s, SIG_DFL);
    // Leave the command nothing of ours but stdio (and the exec-error pipe, close-on-exec).
    const int keep = err_pipe[1];
#ifdef SYS_close_range
    if (syscall(SYS_close_range, 3u, static_cast<unsigned>(keep - 1), 0u) != 0 ||
        syscall(SYS_close_range, static_cast<unsigned>(keep + 1), ~0u, 0u) != 0)
#endif
    {
      const long max_fd = std::min(sysconf(_SC_OPEN_MAX), 65536L);
      for (int fd = 3; fd < max_fd; ++fd) {
        if (fd != keep) close(fd);
      }
    }
    execve(program.c_str(), argv.data(), envp.data());
    const int e = errno;
    ssize_t ignored = write(keep, &e, sizeof(e));
    (void)ignored;
    _exit(127);
  }
  setpgid(pid, pid);  // also from here, so signals to the group work at once
  close(out_pipe[1]);
  close(err_pipe[1]);
  int exec_errno = 0;
  ssize_t n;
  while ((n = read(err_pipe[0], &exec_errno, sizeof(exec_errno))) < 0 && errno == EINTR) {
  }
  close(err_pipe[0]);
  m->out_fd = out_pipe[0];
  fcntl(m->out_fd, F_SETFL, fcntl(m->out_fd, F_GETFL) | O_NONBLOCK);
  m->pid = pid;
  SetGroup(m, pid);
  Board().commands.insert(pid);
  m->state = CommandState::kRunning;
  if (n == static_cast<ssize_t>(sizeof(exec_errno))) {
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    Board().commands.erase(pid);
    m->pid = 0;
    SetGroup(m, 0);
    AppendOutput(m, "[procman] cannot start: exec " + program + ": " + strerror(exec_errno) + "\n");
    OnExit(m, -1, now_s);
  }
}

void Supervisor::BeginStop(Managed* m, double now_s) {
  m->state = CommandState::kStopping;
  m->stop_deadline_s = now_s + m->spec.stop_time_allowed_s;
  m->killed = m->spec.stop_time_allowed_s <= 0;
  SignalTree(m, m->killed ? SIGKILL : m->spec.stop_signal);
}

// wait_status -1: it never ran (start failure, exit code 127).
void Supervisor::OnExit(Managed* m, int wait_status, double now_s) {
  int code = 127;
  if (wait_status >= 0) {
    code = WIFEXITED(wait_status)     ? WEXITSTATUS(wait_status)
           : WIFSIGNALED(wait_status) ? 128 + WTERMSIG(wait_status)
                                      : 1;
  }
  Board().commands.erase(m->pid);
  m->pid = 0;
  m->exit_code = code;
  m->cpu_percent = 0;
  m->rss_bytes = 0;
  ReadOutput(m);
  if (m->state == CommandState::kStopping) return;  // Step() ends the stop once the tree is gone
  // Exited on its own: nothing of it may stay behind.
  if (m->pgid > 0) {
    SignalTree(m, SIGKILL);
    SetGroup(m, 0);
  }
  const bool want = !shutting_down_ && !m->removed && m->spec.desired_running;
  if (want && m->spec.auto_respawn && m->spec.desired_runid == m->actual_runid) {
    if (now_s - m->started_s >= respawn_.stable_run_s) m->quick_crashes = 0;
    const double delay = respawn_.Delay(m->quick_crashes);
    ++m->quick_crashes;
    m->respawn_at_s = now_s + delay;
    m->state = CommandState::kRespawnWait;
    char line[128];
    snprintf(line, sizeof(line), "[procman] exited with code %d; respawning in %.2f s\n", code,
             delay);
    AppendOutput(m, line);
  } else {
    m->state = code == 0 ? CommandState::kStopped : CommandState::kFailed;
    m->exited_on_its_own = true;
    if (wait_status >= 0)
      AppendOutput(m, "[procman] exited with code " + std::to_string(code) + "\n");
  }
}

bool Supervisor::ReapAll(double now_s) {
  bool changed = false;
  while (true) {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid <= 0) break;
    bool mine = false;
    for (auto& m : commands_) {
      if (m->pid == pid) {
        OnExit(m.get(), status, now_s);
        changed = mine = true;
      }
    }
    // Another Supervisor's command: kept for it. Anything else is an orphaned descendant
    // handed to us as subreaper: just reaped.
    if (!mine && Board().commands.count(pid)) Board().statuses[pid] = status;
  }
  for (auto& m : commands_) {
    auto it = m->pid > 0 ? Board().statuses.find(m->pid) : Board().statuses.end();
    if (it == Board().statuses.end()) continue;
    const int status = it->second;
    Board().statuses.erase(it);
    OnExit(m.get(), status, now_s);
    changed = true;
  }
  return changed;
}

bool Supervisor::Step(double now_s) {
  bool changed = ReapAll(now_s);
  for (auto& m : commands_) ReadOutput(m.get());
  for (auto& mp : commands_) {
    Managed* m = mp.get();
    const auto signature = std::make_tuple(m->state, m->pid, m->restart_count, m->exit_code);
    // Two passes so that a stop that completes can be followed by the restart at once.
    for (int pass = 0; pass < 2; ++pass) {
      const bool want = !shutting_down_ && !m->removed && m->spec.desired_running;
      const bool new_run = m->spec.desired_runid != m->actual_runid;
      const CommandState before = m->state;
      switch (m->state) {
        case CommandState::kStarting:
        case CommandState::kRunning:
          if (!want || new_run) BeginStop(m, now_s);
          break;
        case CommandState::kStopping:
          if (m->pid == 0 && !TreeAlive(m)) {
            m->state = CommandState::kStopped;
            SetGroup(m, 0);
            m->tree.clear();
            ReadOutput(m);
          } else if (now_s >= m->stop_deadline_s && !m->killed) {
            AppendOutput(m, "[procman] still running " +
                                std::to_string(m->spec.stop_time_allowed_s) + " s after signal " +
                                std::to_string(m->spec.stop_signal) + "; sending SIGKILL\n");
            SignalTree(m, SIGKILL);
            m->killed = true;
            changed = true;
          } else if (m->killed && now_s >= m->stop_deadline_s + 1.0) {
            SignalTree(m, SIGKILL);  // something new appeared in the tree meanwhile
            m->stop_deadline_s = now_s;
          }
          break;
        case CommandState::kRespawnWait:
          if (!want) {
            m->state = CommandState::kStopped;
          } else if (new_run || now_s >= m->respawn_at_s) {
            if (!new_run) ++m->restart_count;
            Start(m, now_s);
          }
          break;
        case CommandState::kStopped:
        case CommandState::kFailed:
          if (want && (!m->exited_on_its_own || new_run)) Start(m, now_s);
          break;
      }
      if (m->state == before) break;
    }
    // Stopped as ordered: it is in the state of that order (a new sheriff adopts this id).
    const bool want = !shutting_down_ && !m->removed && m->spec.desired_running;
    if (!want && (m->state == CommandState::kStopped || m->state == CommandState::kFailed)) {
      m->actual_runid = m->spec.desired_runid;
    }
    changed =
        changed || signature != std::make_tuple(m->state, m->pid, m->restart_count, m->exit_code);
  }
  // Forget commands no longer ordered, once nothing of them runs.
  const size_t before = commands_.size();
  commands_.erase(std::remove_if(commands_.begin(), commands_.end(),
                                 [](const std::unique_ptr<Managed>& m) {
                                   const bool done = m->removed && m->pid == 0 &&
                                                     (m->state == CommandState::kStopped ||
                                                      m->state == CommandState::kFailed);
                                   if (done && m->out_fd >= 0) close(m->out_fd);
                                   return done;
                                 }),
                  commands_.end());
  last_step_s_ = now_s;
  return changed || commands_.size() != before;
}

double Supervisor::NextWakeup() const {
  double next = std::numeric_limits<double>::infinity();
  for (const auto& m : commands_) {
    if (m->state == CommandState::kRespawnWait) next = std::min(next, m->respawn_at_s);
    if (m->state == CommandState::kStopping) {
      // Leftovers of a stop are not always our children (no SIGCHLD): poll them.
      next = std::min(next, m->killed || m->pid == 0 ? last_step_s_ + 0.05 : m->stop_deadline_s);
    }
  }
  return next;
}

std::vector<int> Supervisor::OutputFds() const {
  std::vector<int> fds;
  for (const auto& m : commands_) {
    if (m->out_fd >= 0) fds.push_back(m->out_fd);
  }
  return fds;
}

void Supervisor::UpdateUsage(double now_s) {
  bool any = false;
  for (const auto& m : commands_) any = any || m->pid > 0;
  if (!any) return;
  const ProcessTable table = ProcessTable::Snapshot();
  const double hz = static_cast<double>(ClockTicksPerSecond());
  for (auto& m : commands_) {
    if (m->pid <= 0) continue;
    uint64_t ticks = 0;
    int64_t rss = 0;
    std::vector<std::pair<int, uint64_t>> tree;
    for (int pid : table.Tree(m->pid, m->pgid)) {
      const ProcInfo& p = table.processes().at(pid);
      ticks += p.ticks + p.child_ticks;
      rss += p.rss_bytes;
      tree.emplace_back(pid, p.start_time);
    }
    // Keep descendants seen before that are still alive but left the tree (reparented).
    for (const auto& old : m->tree) {
      auto it = table.processes().find(old.first);
      if (it != table.processes().end() && it->second.start_time == old.second &&
          std::find(tree.begin(), tree.end(), old) == tree.end()) {
        tree.push_back(old);
      }
    }
    m->tree = std::move(tree);
    if (m->prev_ticks_s >= 0 && now_s > m->prev_ticks_s && ticks >= m->prev_ticks) {
      m->cpu_percent =
          100.0 * static_cast<double>(ticks - m->prev_ticks) / hz / (now_s - m->prev_ticks_s);
    }
    m->prev_ticks = ticks;
    m->prev_ticks_s = now_s;
    m->rss_bytes = rss;
  }
}

std::vector<CommandStatus> Supervisor::Status() const {
  std::vector<CommandStatus> out;
  for (const auto& m : commands_) {
    CommandStatus s;
    s.id = m->spec.id;
    s.group = m->spec.group;
    s.exec = m->spec.exec;
    s.state = m->state;
    s.pid = m->pid;
    s.exit_code = m->exit_code;
    s.restart_count = m->restart_count;
    s.actual_runid = m->actual_runid;
    s.cpu_percent = m->cpu_percent;
    s.rss_bytes = m->rss_bytes;
    s.auto_respawn = m->spec.auto_respawn;
    out.push_back(s);
  }
  return out;
}

const CommandSpec* Supervisor::FindSpec(const std::string& id) const {
  for (const auto& m : commands_) {
    if (m->spec.id == id && !m->removed) return &m->spec;
  }
  return nullptr;
}

std::vector<std::pair<std::string, std::string>> Supervisor::TakeOutput(size_t max_bytes) {
  std::vector<std::pair<std::string, std::string>> out;
  for (auto& m : commands_) {
    if (m->output.empty() && m->output_dropped == 0) continue;
    std::string text;
    if (m->output_dropped > 0) {
      text = "[procman] " + std::to_string(m->output_dropped) + " bytes of output dropped\n";
      m->output_dropped = 0;
    }
    const size_t n = std::min(m->output.size(), max_bytes);
    text += m->output.substr(0, n);
    m->output.erase(0, n);
    out.emplace_back(m->spec.id, std::move(text));
  }
  return out;
}

}  // namespace procman
}  // namespace sarmap
