// sarmap-procman: the sheriff. Sends the desired state of a .pmd config to the deputies and
// shows what they report.
//
//   sarmap-procman CONFIG.pmd status
//   sarmap-procman CONFIG.pmd start|stop|restart NAME     (command, group, or "everything")
//   sarmap-procman CONFIG.pmd run SCRIPT
//   sarmap-procman CONFIG.pmd                             (live status table + output tail)
//   sarmap-procman CONFIG.pmd --observer                  (live view, sends nothing)
//   sarmap-procman CONFIG.pmd --lone-ranger [COMMAND]     (deputies in-process: one computer)
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include "common/args.h"
#include "common/lcm_guard.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/time.h"
#include "procman/cli_common.h"
#include "procman/deputy.h"
#include "procman/procman_cli.h"
#include "procman/sheriff.h"
#include "procman/supervisor.h"

namespace sarmap {
namespace procman {

namespace {

std::string HostName() {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  return host;
}

std::vector<std::string> Words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

// What the program does on top of the sheriff: a one-shot command, a script, the live view.
class Driver : public EventLoop::Participant {
 public:
  Driver(Sheriff* sheriff, const ProcmanOptions& options, bool live_after, bool interactive)
      : sheriff_(sheriff), options_(options), live_after_(live_after), interactive_(interactive) {}

  void SetRunner(std::unique_ptr<ScriptRunner> runner) { runner_ = std::move(runner); }
  void SetStatusOnly() { status_only_ = true; }

  void AddFds(std::vector<pollfd>* fds) override {
    if (live_ && interactive_ && stdin_open_) fds->push_back({0, POLLIN, 0});
  }
  double NextWakeup() const override {
    double next = runner_ ? runner_->NextWakeup() : 1e300;
    if (live_)
      next = std::min(next, events_ ? sheriff_->NextLostDeadline(Now()) + 0.001 : next_draw_s_);
    if (settling_ || status_only_) next = std::min(next, Now() + 0.1);
    return next;
  }

  void OnWake(const std::vector<pollfd>& fds, double now_s) override {
    if (start_s_ < 0) start_s_ = now_s;
    for (const auto& p : fds) {
      if (p.fd == 0 && (p.revents & (POLLIN | POLLHUP))) ReadStdin();
    }
    if (status_only_) {
      if (sheriff_->AllDeputiesHeard() || now_s - start_s_ > options_.discovery_timeout_s) {
        std::cout << sheriff_->Table(now_s) << std::flush;
        Finish(0);
      }
      return;
    }
    if (runner_) {
      const ScriptRunner::Result r = runner_->Step(now_s);
      if (r == ScriptRunner::kFailed) {
        std::cerr << "sarmap-procman: " << runner_->error() << "\n";
        message_ = runner_->error();
        runner_.reset();
        if (!live_after_) {
          std::cout << sheriff_->Table(now_s) << std::flush;
          Finish(1);
          return;
        }
      } else if (r == ScriptRunner::kDone) {
        runner_.reset();
        settling_ = true;
        settle_start_s_ = now_s;
      }
    }
    if (settling_) {
      std::string why;
      if (sheriff_->Settled(&why)) {
        settling_ = false;
        if (!live_after_) {
          std::cout << sheriff_->Table(now_s) << std::flush;
          Finish(0);
          return;
        }
        message_ = "done";
      } else if (now_s - settle_start_s_ >
                 options_.discovery_timeout_s + options_.command_timeout_s) {
        std::cerr << "sarmap-procman: " << why << "\n";
        settling_ = false;
        if (!live_after_) {
          std::cout << sheriff_->Table(now_s) << std::flush;
          Finish(1);
          return;
        }
      }
    }
    if (!runner_ && !settling_ && live_after_) live_ = true;
    if (live_ && events_) {
      PrintEvents(now_s);
    } else if (live_ && now_s >= next_draw_s_) {
      Draw(now_s);
      next_draw_s_ = now_s + 1.0;
    }
  }

  bool finished() const { return finished_; }
  int exit_code() const { return exit_code_; }

 private:
  void Finish(int code) {
    finished_ = true;
    exit_code_ = code;
  }

  // Live view without a terminal (a log, systemd, tests): one time-stamped line per change.
  void PrintEvents(double now_s) {
    const double wall_s = static_cast<double>(common::WallClockUtime()) * 1e-6;
    char stamp[32];
    snprintf(stamp, sizeof(stamp), "[%.3f] ", wall_s);
    for (const auto& id : sheriff_->config().Deputies()) {
      const std::string state = !sheriff_->DeputyHeard(id)        ? "not seen"
                                : sheriff_->DeputyLost(id, now_s) ? "LOST"
                                                                  : "ok";
      std::string& last = deputy_state_[id];
      if (state != last) {
        if (state == "LOST") {
          std::cout << stamp << "deputy '" << id << "' LOST (silent for more than "
                    << options_.deputy_lost_after_s << " s)\n";
        } else if (state == "ok") {
          std::cout << stamp << "deputy '" << id << "' " << (last == "LOST" ? "back" : "seen")
                    << "\n";
        }
        last = state;
      }
    }
    for (const auto& c : sheriff_->config().commands) {
      const int state = sheriff_->CommandState(c.id);
      const int pid = sheriff_->CommandPid(c.id);
      auto& last = command_state_[c.id];
      if (state >= 0 && (state != last.first || pid != last.second)) {
        std::cout << stamp << "command '" << c.id << "' on '" << c.deputy
                  << "': " << ToString(static_cast<CommandState>(state))
                  << (pid > 0 ? " pid " + std::to_string(pid) : "") << "\n";
        last = {state, pid};
      }
    }
    std::cout << std::flush;
  }

  void Draw(double now_s) {
    std::ostringstream out;
    if (isatty(1)) out << "\033[H\033[2J";
    out << "sarmap-procman  " << sheriff_->config().source
        << (sheriff_->observer() ? "  (observer)" : "") << "\n\n";
    out << sheriff_->Table(now_s);
    if (runner_) out << "\n" << runner_->Describe() << "\n";
    if (options_.output_tail_lines > 0) {
      out << "\n--- output (last " << options_.output_tail_lines << " lines) ---\n"
          << sheriff_->OutputTail(options_.output_tail_lines);
    }
    if (!message_.empty()) out << "\n" << message_ << "\n";
    if (interactive_ && !sheriff_->observer()) {
      out << "\n[start|stop|restart NAME, run SCRIPT, output NAME, quit] > ";
    }
    std::cout << out.str() << std::flush;
  }

  void ReadStdin() {
    char buf[1024];
    const ssize_t n = read(0, buf, sizeof(buf));
    if (n <= 0) {
      stdin_open_ = false;
      return;
    }
    line_.append(buf, static_cast<size_t>(n));
    size_t nl;
    while ((nl = line_.find('\n')) != std::string::npos) {
      Execute(Words(line_.substr(0, nl)));
      line_.erase(0, nl + 1);
      next_draw_s_ = 0;
    }
  }

  void Execute(const std::vector<std::string>& w) {
    if (w.empty()) return;
    try {
      if (w[0] == "quit" || w[0] == "q" || w[0] == "exit") {
        Finish(0);
      } else if (w[0] == "output" && w.size() == 2) {
        message_ = "--- output of " + w[1] + " ---\n" + sheriff_->OutputTail(40, w[1]);
      } else if (sheriff_->observer()) {
        message_ = "observer: sends no orders";
      } else if ((w[0] == "start" || w[0] == "stop" || w[0] == "restart") && w.size() == 2) {
        const Target t = sheriff_->config().ResolveTarget(w[1]);
        sheriff_->Apply(w[0] == "start"  ? Sheriff::Verb::kStart
                        : w[0] == "stop" ? Sheriff::Verb::kStop
                                         : Sheriff::Verb::kRestart,
                        t);
        message_ = w[0] + " " + t.ToString();
      } else if (w[0] == "run" && w.size() == 2) {
        const Script* s = sheriff_->config().FindScript(w[1]);
        if (!s) throw ConfigError("no script \"" + w[1] + "\"");
        runner_ = std::make_unique<ScriptRunner>(sheriff_, s);
        message_ = "running script \"" + w[1] + "\"";
      } else {
        message_ = "commands: start|stop|restart NAME, run SCRIPT, output NAME, quit";
      }
    } catch (const ConfigError& e) {
      message_ = e.what();
    }
  }

  Sheriff* sheriff_;
  ProcmanOptions options_;
  bool live_after_;
  bool interactive_;
  bool live_ = false;
  bool status_only_ = false;
  bool settling_ = false;
  bool stdin_open_ = true;
  double start_s_ = -1;
  double settle_start_s_ = 0;
  double next_draw_s_ = 0;
  std::unique_ptr<ScriptRunner> runner_;
  std::string line_;
  std::string message_;
  bool finished_ = false;
  int exit_code_ = 0;
  const bool events_ = !isatty(1);
  std::map<std::string, std::string> deputy_state_;
  std::map<std::string, std::pair<int, int>> command_state_;
};

}  // namespace

int RunSheriff(int argc, char** argv) {
  common::ArgParser parser(
      "sarmap-procman",
      "The procman sheriff: sends the desired state of a .pmd config to its deputies "
      "(signed) and shows their state.");
  common::NodeArgs node_args;
  std::string pmd_path, command, target;
  std::string key_path;
  std::string sheriff_name = "sheriff@" + HostName();
  bool observer = false, lone_ranger = false;
  parser.AddPositional("CONFIG.pmd", &pmd_path, "procman launch configuration");
  parser.AddPositional(
      "COMMAND", &command,
      "status | start NAME | stop NAME | restart NAME | run SCRIPT; none: live view", false);
  parser.AddPositional("NAME", &target,
                       "command, group (\"group:NAME\" if ambiguous), everything; or script",
                       false);
  parser.AddFlag("--key", &key_path,
                 "shared HMAC key file (default: key_file of the options; see README: key set-up)");
  parser.AddFlag(
      "--sheriff-id", &sheriff_name,
      "sheriff name (each run adds /PID); deputies check order counters per name, see README");
  parser.AddSwitch("--observer", &observer, "only watch: send no orders (no key needed)");
  parser.AddSwitch("--lone-ranger", &lone_ranger,
                   "run the config's deputies inside this process (one computer, one command); "
                   "stays up after COMMAND, Ctrl-C stops everything");
  parser.AddNodeOptions(&node_args);
  parser.SetEpilog(
      "examples:\n"
      "  sarmap-procman launch-scripts/sim-demo.pmd --lone-ranger run start\n"
      "  sarmap-procman launch-scripts/robot-two-computers.pmd status\n"
      "  sarmap-procman launch-scripts/robot-two-computers.pmd restart compute/mapping\n"
      "exit code of one-shot commands: 0 when done, 1 when a wait timed out, 2 on bad use.");
  const std::optional<ProcmanOptions> parsed =
      ParseCommandLine(&parser, &node_args, argc, argv, "sarmap-procman", &key_path);
  if (!parsed) return 0;  // --help or --print-config
  const ProcmanOptions& options = *parsed;
  Config config;
  try {
    config = LoadConfigFile(pmd_path);
  } catch (const ConfigError& e) {
    throw common::ArgError(e.what());
  }

  // What to do.
  std::unique_ptr<ScriptAction> action;
  const Script* script = nullptr;
  bool status_only = false;
  try {
    if (command == "status") {
      status_only = true;
      if (!target.empty()) throw common::ArgError("status takes no NAME");
    } else if (command == "start" || command == "stop" || command == "restart") {
      if (target.empty()) throw common::ArgError(command + " needs a command or group NAME");
      action = std::make_unique<ScriptAction>();
      action->kind = command == "start"  ? ScriptAction::kStart
                     : command == "stop" ? ScriptAction::kStop
                                         : ScriptAction::kRestart;
      action->target = config.ResolveTarget(target);
      action->wait_status = command == "stop" ? "stopped" : "running";
      action->timeout_s = options.command_timeout_s;
    } else if (command == "run") {
      script = config.FindScript(target);
      if (!script) throw common::ArgError(pmd_path + ": no script \"" + target + "\"");
    } else if (!command.empty()) {
      throw common::ArgError("unknown command '" + command +
                             "' (status, start, stop, restart, run)");
    }
  } catch (const ConfigError& e) {
    throw common::ArgError(e.what());
  }
  if (observer && (action || script))
    throw common::ArgError("--observer sends no orders; only status or live view");
  if (observer && lone_ranger)
    throw common::ArgError("--observer and --lone-ranger exclude each other");
  // status only watches: no key needed.
  const bool watch_only = observer || (status_only && !lone_ranger);
  Key key;
  if (!watch_only) key = LoadKeyFileOrArgError(key_path);
  const std::string sheriff_id = sheriff_name + "/" + std::to_string(getpid());

  const std::string url = node_args.lcm_url.empty() ? common::DefaultLcmUrl() : node_args.lcm_url;
  lcm::LCM lcm(url);
  if (!lcm.good()) throw std::runtime_error("cannot initialise LCM on '" + url + "'");
  EventLoop loop(&lcm);

  const bool one_shot = action || script || status_only;
  const bool live_after = lone_ranger || !one_shot;
  Sheriff sheriff(&lcm, options, config, watch_only ? nullptr : &key, sheriff_id);
  common::AuthKey bus_key;
  if (!node_args.bus_key_file.empty()) {
    try {
      bus_key = common::LoadAuthKeyFile(node_args.bus_key_file);
    } catch (const std::runtime_error& e) {
      throw common::ArgError(e.what());
    }
    sheriff.SetBusKey(bus_key);
  }
  std::string guard_error;  // hostile LCM fragments (common/lcm_guard.h)
  if (common::GuardLcmReceiveSocket(&lcm, url, &guard_error) < 0) {
    SARMAP_LOG(WARN) << "no filter for hostile LCM fragments: " << guard_error;
  }
  Driver driver(&sheriff, options, live_after, isatty(0) != 0);
  if (status_only && !lone_ranger) driver.SetStatusOnly();
  if (action) driver.SetRunner(std::make_unique<ScriptRunner>(&sheriff, *action));
  if (script) driver.SetRunner(std::make_unique<ScriptRunner>(&sheriff, script));
  // The driver first: what it changes is sent by the sheriff in the same wake-up.
  loop.Add(&driver);
  loop.Add(&sheriff);

  std::vector<std::unique_ptr<Deputy>> deputies;
  if (lone_ranger) {
    if (!BecomeSubreaper()) {
      SARMAP_LOG(WARN) << "cannot become child subreaper; orphans go to init";
    }
    if (!StartGroupGuardian()) {
      SARMAP_LOG(WARN) << "no group guardian (" << strerror(errno)
                       << "): if this process is killed, what its commands forked runs on";
    }
    for (const auto& id : config.Deputies()) {
      deputies.push_back(
          std::make_unique<Deputy>(&lcm, options, id, key, InheritedEnvironment(OwnDirectory())));
      if (!bus_key.empty()) deputies.back()->SetBusKey(bus_key);
      loop.Add(deputies.back().get());
    }
  }

  int code = 0;
  while (true) {
    if (!loop.RunOnce(1.0)) return 1;
    const int interrupts = EventLoop::Interrupts();
    if (driver.finished() && deputies.empty()) {
      code = driver.exit_code();
      break;
    }
    if (interrupts >= 1 || driver.finished()) {
      if (deputies.empty()) return 130;
      bool all_done = true;
      for (auto& d : deputies) {
        d->Shutdown();
        all_done = all_done && d->Finished();
      }
      if (all_done || interrupts >= 2) break;
    }
  }
  if (isatty(1) && live_after) std::cout << "\n";
  return code;
}

}  // namespace procman
}  // namespace sarmap
