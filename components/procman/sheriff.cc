#include "procman/sheriff.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <sstream>

#include "common/bus_publish.h"
#include "common/decode.h"
#include "common/logging.h"
#include "procman/launcher_header.h"
#include "procman/supervisor.h"

namespace sarmap {
namespace procman {

using sarmap::pm_command_status_t;

struct Sheriff::CommandView {
  CommandConfig cfg;
  bool desired_running = false;
  int32_t desired_runid = 0;
  bool has_pending = false;  // asked before its deputy was heard
  Verb pending = Verb::kStart;
  bool reported = false;
  pm_command_status_t status;
  std::string partial_line;  // output not yet ended by a newline
};

struct Sheriff::DeputyView {
  std::string id;
  bool heard = false;
  double last_heard_s = 0;
  int64_t session = 0;       // confirmed session (0: none yet)
  int64_t clock_us = 0;      // its session clock in the last verified report
  double clock_heard_s = 0;  // when that report arrived (steady clock)
  // Other sheriffs' last followed orders to this deputy (their counters are on its clock).
  std::map<std::string, int64_t> foreign_counters;
  sarmap::pm_info_t info;
  bool initialised = false;    // desired state adopted from its first report
  bool dirty = false;          // desired state changed, not sent yet
  int64_t change_counter = 0;  // counter of the first orders sent after the last change
  int64_t last_sent_counter = 0;
};

namespace {

bool Active(const pm_command_status_t& s) {
  return s.state == pm_command_status_t::STATE_RUNNING ||
         s.state == pm_command_status_t::STATE_STARTING ||
         s.state == pm_command_status_t::STATE_RESPAWN_WAIT;
}

bool Down(const pm_command_status_t& s) {
  return s.state == pm_command_status_t::STATE_STOPPED ||
         s.state == pm_command_status_t::STATE_FAILED;
}

std::string Mb(int64_t bytes) {
  char buf[32];
  snprintf(buf, sizeof(buf), "%.1f", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return buf;
}

}  // namespace

Sheriff::Sheriff(lcm::LCM* lcm, const ProcmanOptions& options, Config config, const Key* key,
                 std::string sheriff_id)
    : lcm_(lcm),
      options_(options),
      config_(std::move(config)),
      key_(key),
      sheriff_id_(std::move(sheriff_id)) {
  for (const auto& c : config_.commands) {
    auto v = std::make_unique<CommandView>();
    v->cfg = c;
    commands_.push_back(std::move(v));
  }
  for (const auto& d : config_.Deputies()) {
    auto v = std::make_unique<DeputyView>();
    v->id = d;
    deputies_.push_back(std::move(v));
  }
  subscriptions_.push_back(
      lcm_->subscribe("^" + options_.info_channel + "$", &Sheriff::OnInfo, this));
  subscriptions_.push_back(
      lcm_->subscribe("^" + options_.output_channel + "$", &Sheriff::OnOutput, this));
  if (key_)
    subscriptions_.push_back(
        lcm_->subscribe("^" + options_.orders_channel + "$", &Sheriff::OnOrders, this));
  SendProbe();
}

void Sheriff::SendProbe() {
  sarmap::pm_orders_t probe;
  probe.header = LauncherHeader(&orders_seq_);
  probe.sheriff_id = sheriff_id_;
  probe.deputy_id = kProbeDeputyId;
  probe.deputy_session = 0;
  probe.counter = 0;
  probe.num_commands = 0;
  std::fill(std::begin(probe.hmac_sha256), std::end(probe.hmac_sha256), 0);
  if (key_) {
    // A fresh nonce that the deputies echo: a report carrying it is live, not a recording.
    probe.counter = RandomNonce();
    info_guard_.AddChallenge(probe.counter);
    SignOrders(*key_, &probe);
  }
  common::PublishOnBus(lcm_, &bus_auth_, options_.orders_channel, probe);
  ++probes_sent_;
  last_probe_s_ = Now();
  next_probe_s_ = last_probe_s_ + 0.25;
}

Sheriff::~Sheriff() {
  for (auto* s : subscriptions_) lcm_->unsubscribe(s);
}

Sheriff::DeputyView* Sheriff::FindDeputy(const std::string& id) {
  for (auto& d : deputies_) {
    if (d->id == id) return d.get();
  }
  return nullptr;
}
const Sheriff::DeputyView* Sheriff::FindDeputy(const std::string& id) const {
  for (const auto& d : deputies_) {
    if (d->id == id) return d.get();
  }
  return nullptr;
}
const Sheriff::CommandView* Sheriff::FindCommand(const std::string& id) const {
  for (const auto& c : commands_) {
    if (c->cfg.id == id) return c.get();
  }
  return nullptr;
}

template <class T>
bool Sheriff::Decode(const lcm::ReceiveBuffer* rbuf, const std::string& channel, T* msg) {
  std::string why;
  if (common::DecodeMessage(rbuf->data, rbuf->data_size, msg, &why)) return true;
  ++malformed_;
  long suppressed = 0;
  if (drop_log_limit_.try_emplace(channel, 5.0).first->second.Allow(Now(), &suppressed)) {
    SARMAP_LOG(WARN) << "dropped a message on " << common::EscapeForLog(channel) << ": "
                     << common::EscapeForLog(why, 512) << " (so far " << malformed_ << ")";
  }
  return false;
}

void Sheriff::OnInfo(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  sarmap::pm_info_t info;
  if (!Decode(rbuf, channel, &info)) return;
  DeputyView* d = FindDeputy(info.deputy_id);
  if (!d) return;  // a deputy this config does not use
  const double now = Now();
  if (key_) {
    const InfoVerdict verdict = info_guard_.Verify(*key_, info);
    if (verdict == InfoVerdict::kUnconfirmed) {
      // A deputy that restarted, or a recording of an earlier run: a probe tells them apart.
      if (now - last_probe_s_ >= 0.25) SendProbe();
      return;
    }
    if (verdict != InfoVerdict::kAccepted && verdict != InfoVerdict::kNewSession) {
      ++ignored_info_;
      long suppressed = 0;
      if (drop_log_limit_.try_emplace("info", 60.0).first->second.Allow(now, &suppressed)) {
        SARMAP_LOG(WARN) << "IGNORED a report on " << common::EscapeForLog(channel)
                         << " claiming deputy '" << common::EscapeForLog(info.deputy_id)
                         << "': " << ToString(verdict)
                         << "; only signed, live reports count (ignored so far: " << ignored_info_
                         << ")";
      }
      return;
    }
    if (verdict == InfoVerdict::kNewSession) {
      if (d->session != 0) {
        SARMAP_LOG(WARN) << "deputy '" << d->id << "' restarted (new session): sending it the "
                         << "desired state again";
        if (d->initialised) d->dirty = true;
      }
      d->session = info.session;
      d->last_sent_counter = 0;
      d->change_counter = 0;
      d->foreign_counters.clear();
    }
  } else {
    d->session = info.session;  // an observer shows what it hears; it decides nothing
  }
  d->clock_us = info.session_clock_us;
  d->clock_heard_s = now;
  d->heard = true;
  d->last_heard_s = now;
  d->info = info;
  for (auto& c : commands_) {
    if (c->cfg.deputy != d->id) continue;
    c->reported = false;
    for (const auto& s : info.commands) {
      if (s.command_id == c->cfg.id) {
        c->status = s;
        c->reported = true;
      }
    }
  }
  if (!d->initialised) Adopt(d);
}

void Sheriff::Adopt(DeputyView* d) {
  // Take what runs as the desired state: sending it back changes nothing.
  for (auto& c : commands_) {
    if (c->cfg.deputy != d->id) continue;
    c->desired_running = c->reported && Active(c->status);
    c->desired_runid = c->reported ? c->status.actual_runid : 0;
  }
  std::string strangers;
  for (const auto& s : d->info.commands) {
    const CommandView* c = FindCommand(s.command_id);
    if (!c || c->cfg.deputy != d->id) strangers += " " + common::EscapeForLog(s.command_id);
  }
  d->initialised = true;
  if (!strangers.empty() && !observer()) {
    SARMAP_LOG(WARN) << "deputy '" << d->id << "' runs commands not in " << config_.source << ":"
                     << strangers << "; they will be stopped";
    d->dirty = true;
  }
  for (auto& c : commands_) {
    if (c->cfg.deputy == d->id && c->has_pending) {
      c->has_pending = false;
      ApplyTo(c->pending, c.get(), d);
    }
  }
}

void Sheriff::OnOutput(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  sarmap::pm_output_t out;
  if (!Decode(rbuf, channel, &out)) return;
  if (!FindDeputy(out.deputy_id)) return;  // a deputy this config does not use
  if (key_) {
    // Only the deputy's own lines, of its current session, each message once: a forger cannot
    // put lines into a command's output.
    const InfoVerdict verdict = info_guard_.VerifyOutput(*key_, out);
    // Signed, of a session not confirmed yet: the deputy's output before this sheriff has heard
    // its echo (at start, after a deputy restart), or a recording. Dropped, not alarming.
    if (verdict == InfoVerdict::kUnconfirmed) return;
    if (verdict != InfoVerdict::kAccepted) {
      ++ignored_output_;
      long suppressed = 0;
      if (drop_log_limit_.try_emplace("output", 60.0).first->second.Allow(Now(), &suppressed)) {
        SARMAP_LOG(WARN) << "IGNORED output on " << common::EscapeForLog(channel)
                         << " claiming deputy '" << common::EscapeForLog(out.deputy_id)
                         << "': " << ToString(verdict)
                         << "; only signed output of the deputy's current session is shown "
                            "(ignored so far: "
                         << ignored_output_ << ")";
      }
      return;
    }
  }
  for (int i = 0; i < out.num_commands; ++i) {
    CommandView* c = nullptr;
    for (auto& v : commands_) {
      if (v->cfg.id == out.command_ids[i] && v->cfg.deputy == out.deputy_id) c = v.get();
    }
    if (!c) continue;
    c->partial_line += out.text[i];
    size_t nl;
    while ((nl = c->partial_line.find('\n')) != std::string::npos) {
      tail_.emplace_back(c->cfg.id, c->partial_line.substr(0, nl));
      c->partial_line.erase(0, nl + 1);
    }
    if (c->partial_line.size() > 4096) {  // a very long line without newline
      tail_.emplace_back(c->cfg.id, c->partial_line);
      c->partial_line.clear();
    }
  }
  while (tail_.size() > 2000) tail_.pop_front();
}

void Sheriff::OnOrders(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  sarmap::pm_orders_t orders;
  if (!Decode(rbuf, channel, &orders) || orders.sheriff_id == sheriff_id_) return;
  DeputyView* d = FindDeputy(orders.deputy_id);
  if (!d || d->session == 0 || IsUnsigned(orders.hmac_sha256) || !SignatureValid(*key_, orders))
    return;
  // The deputy's own rules: its session, within the window of its clock, counters going up.
  const int64_t clock_us = EstimatedDeputyClockUs(*d, Now());
  const int64_t window_us = static_cast<int64_t>(options_.order_window_s * 1e6);
  if (orders.deputy_session != d->session || orders.counter < clock_us - window_us ||
      orders.counter > clock_us + window_us)
    return;
  auto it = d->foreign_counters.find(orders.sheriff_id);
  if (it != d->foreign_counters.end() && orders.counter <= it->second) return;
  d->foreign_counters[orders.sheriff_id] = orders.counter;
  // Sheriffs silent for longer than the window are forgotten (their orders fail the window).
  for (auto f = d->foreign_counters.begin(); f != d->foreign_counters.end();) {
    f = f->second < clock_us - window_us ? d->foreign_counters.erase(f) : std::next(f);
  }
  // Another sheriff (e.g. a one-shot command) changed the desired state: follow it. Every
  // change bumps the command's run id, so a higher run id is a newer change; a periodic
  // re-send carries the old one and never undoes our change. Two changes made at once from
  // the same run id: the later orders win.
  for (const auto& o : orders.commands) {
    for (auto& c : commands_) {
      if (c->cfg.id != o.command_id || c->cfg.deputy != d->id) continue;
      const bool newer =
          o.desired_runid > c->desired_runid ||
          (o.desired_runid == c->desired_runid && orders.counter > d->last_sent_counter);
      if (newer) {
        c->desired_running = o.desired_running;
        c->desired_runid = o.desired_runid;
      }
    }
  }
  if (!d->initialised) {
    d->initialised = true;
    // What we were asked before knowing this deputy applies on top.
    for (auto& c : commands_) {
      if (c->cfg.deputy == d->id && c->has_pending) {
        c->has_pending = false;
        ApplyTo(c->pending, c.get(), d);
      }
    }
  }
}

bool Sheriff::Acknowledged(const DeputyView& d) const {
  return d.initialised && !d.dirty && d.heard && d.info.last_order_counter >= d.change_counter;
}

void Sheriff::ApplyTo(Verb verb, CommandView* c, DeputyView* d) {
  if (!d->initialised) {
    c->has_pending = true;
    c->pending = verb;
    return;
  }
  const int32_t next_runid =
      std::max(c->desired_runid, c->reported ? c->status.actual_runid : 0) + 1;
  switch (verb) {
    case Verb::kStart:
      if (!c->desired_running) {
        c->desired_running = true;
        c->desired_runid = next_runid;
      } else if (Acknowledged(*d) && c->reported && Down(c->status)) {
        c->desired_runid = next_runid;  // it ended on its own: run it again
      } else {
        return;  // already on its way
      }
      break;
    case Verb::kStop:
      if (!c->desired_running) return;
      c->desired_running = false;
      c->desired_runid = next_runid;  // every change is a new version
      break;
    case Verb::kRestart:
      c->desired_running = true;
      c->desired_runid = next_runid;
      break;
  }
  d->dirty = true;
}

void Sheriff::Apply(Verb verb, const Target& target) {
  for (const CommandConfig* cfg : config_.Select(target)) {
    for (auto& c : commands_) {
      if (c->cfg.id == cfg->id) ApplyTo(verb, c.get(), FindDeputy(cfg->deputy));
    }
  }
}

bool Sheriff::Reached(const Target& target, const std::string& status, double now_s,
                      std::string* why_not) const {
  for (const CommandConfig* cfg : config_.Select(target)) {
    const DeputyView* d = FindDeputy(cfg->deputy);
    const CommandView* c = FindCommand(cfg->id);
    std::string why;
    if (!d->heard) {
      why = "deputy '" + d->id + "' not heard";
    } else if (DeputyLost(d->id, now_s)) {
      why = "deputy '" + d->id + "' lost";
    } else if (!Acknowledged(*d)) {
      why = "deputy '" + d->id + "' has not acknowledged the orders yet";
    } else if (status == "running"
                   ? !(c->reported && c->status.state == pm_command_status_t::STATE_RUNNING)
                   : (c->reported && !Down(c->status))) {
      why = "'" + c->cfg.id + "' is " +
            (c->reported ? ToString(static_cast<procman::CommandState>(c->status.state))
                         : "not on its deputy") +
            (c->reported && c->status.exit_code != 0
                 ? " (last exit code " + std::to_string(c->status.exit_code) + ")"
                 : "");
    }
    if (!why.empty()) {
      if (why_not) *why_not = why;
      return false;
    }
  }
  return true;
}

bool Sheriff::Settled(std::string* why_not) const {
  for (const auto& c : commands_) {
    if (c->has_pending) {
      if (why_not) *why_not = "deputy '" + c->cfg.deputy + "' not heard; its orders were not sent";
      return false;
    }
  }
  for (const auto& d : deputies_) {
    if (d->initialised && (d->dirty || d->info.last_order_counter < d->change_counter)) {
      if (why_not) *why_not = "deputy '" + d->id + "' has not acknowledged the orders";
      return false;
    }
  }
  return true;
}

bool Sheriff::AllDeputiesHeard() const {
  for (const auto& d : deputies_) {
    if (!d->heard) return false;
  }
  return true;
}

bool Sheriff::DeputyLost(const std::string& deputy_id, double now_s) const {
  const DeputyView* d = FindDeputy(deputy_id);
  return !d || !d->heard || now_s - d->last_heard_s > options_.deputy_lost_after_s;
}

bool Sheriff::DeputyGone(const std::string& deputy_id, double now_s) const {
  const DeputyView* d = FindDeputy(deputy_id);
  return d && d->heard && now_s - d->last_heard_s > options_.deputy_gone_after_s;
}

bool Sheriff::TargetDeputyGone(const Target& target, double now_s, std::string* why) const {
  for (const CommandConfig* cfg : config_.Select(target)) {
    const DeputyView* d = FindDeputy(cfg->deputy);
    if (d && DeputyGone(d->id, now_s)) {
      char buf[160];
      snprintf(buf, sizeof(buf), "deputy '%s' silent for %.1f s (killed, crashed or cut off)",
               d->id.c_str(), now_s - d->last_heard_s);
      if (why) *why = std::string(buf) + "; the state of its commands is unknown";
      return true;
    }
  }
  return false;
}

bool Sheriff::DeputyHeard(const std::string& deputy_id) const {
  const DeputyView* d = FindDeputy(deputy_id);
  return d && d->heard;
}

double Sheriff::NextLostDeadline(double now_s) const {
  double next = std::numeric_limits<double>::infinity();
  for (const auto& d : deputies_) {
    if (d->heard && !DeputyLost(d->id, now_s))
      next = std::min(next, d->last_heard_s + options_.deputy_lost_after_s);
  }
  return next;
}

int Sheriff::RefusedOrders(const std::string& deputy_id) const {
  const DeputyView* d = FindDeputy(deputy_id);
  return d && d->heard ? d->info.refused_orders : 0;
}

int Sheriff::CommandState(const std::string& command_id) const {
  const CommandView* c = FindCommand(command_id);
  return c && c->reported ? c->status.state : -1;
}

int Sheriff::CommandPid(const std::string& command_id) const {
  const CommandView* c = FindCommand(command_id);
  return c && c->reported ? c->status.pid : 0;
}

int64_t Sheriff::EstimatedDeputyClockUs(const DeputyView& d, double now_s) const {
  return d.clock_us + static_cast<int64_t>((now_s - d.clock_heard_s) * 1e6);
}

void Sheriff::SendOrders(DeputyView* d, double now_s) {
  sarmap::pm_orders_t orders;
  orders.header = LauncherHeader(&orders_seq_);
  orders.sheriff_id = sheriff_id_;
  orders.deputy_id = d->id;
  orders.deputy_session = d->session;
  orders.counter = std::max(d->last_sent_counter + 1, EstimatedDeputyClockUs(*d, now_s));
  for (const auto& c : commands_) {
    if (c->cfg.deputy != d->id) continue;
    sarmap::pm_command_order_t o;
    o.command_id = c->cfg.id;
    o.group = c->cfg.group;
    o.exec = c->cfg.exec;
    o.use_shell = c->cfg.use_shell;
    o.auto_respawn = c->cfg.auto_respawn;
    o.stop_signal = c->cfg.stop_signal;
    o.stop_time_allowed_s = c->cfg.stop_time_allowed_s;
    o.desired_running = c->desired_running;
    o.desired_runid = c->desired_runid;
    orders.commands.push_back(o);
  }
  orders.num_commands = static_cast<int32_t>(orders.commands.size());
  std::fill(std::begin(orders.hmac_sha256), std::end(orders.hmac_sha256), 0);
  SignOrders(*key_, &orders);
  common::PublishOnBus(lcm_, &bus_auth_, options_.orders_channel, orders);
  if (d->dirty) d->change_counter = orders.counter;
  d->dirty = false;
  d->last_sent_counter = orders.counter;
}

void Sheriff::OnWake(const std::vector<pollfd>&, double now_s) {
  // A second probe, in case the first went out before a deputy was listening.
  if (probes_sent_ < 2 && now_s >= next_probe_s_) SendProbe();
  if (observer()) return;
  const bool resend = now_s >= next_resend_s_;
  for (auto& d : deputies_) {
    if (d->initialised && (d->dirty || resend)) SendOrders(d.get(), now_s);
  }
  if (resend) next_resend_s_ = now_s + options_.resend_period_s;
}

double Sheriff::NextWakeup() const {
  if (probes_sent_ < 2) return next_probe_s_;
  if (observer()) return std::numeric_limits<double>::infinity();
  for (const auto& d : deputies_) {
    if (d->initialised && d->dirty) return 0;
  }
  return next_resend_s_;
}

std::string Sheriff::Table(double now_s) const {
  std::ostringstream out;
  char line[512];
  snprintf(line, sizeof(line), "%-14s %-16s %-9s %9s %8s %10s %8s\n", "DEPUTY", "HOST", "STATE",
           "LAST SEEN", "CPU LOAD", "MEM FREE", "REFUSED");
  out << line;
  for (const auto& d : deputies_) {
    if (!d->heard) {
      snprintf(line, sizeof(line), "%-14s %-16s %-9s\n", d->id.c_str(), "-", "not seen");
    } else {
      snprintf(line, sizeof(line), "%-14s %-16s %-9s %7.1f s %7.0f%% %7s MB %8d\n", d->id.c_str(),
               common::EscapeForLog(d->info.host, 64).c_str(),
               DeputyLost(d->id, now_s) ? "LOST" : "ok", now_s - d->last_heard_s,
               100.0 * d->info.cpu_load, Mb(d->info.phys_mem_free_bytes).c_str(),
               d->info.refused_orders);
    }
    out << line;
  }
  if (ignored_info_ > 0) {
    out << ignored_info_ << " unsigned, forged or played-back PM_INFO reports ignored\n";
  }
  if (ignored_output_ > 0) {
    out << ignored_output_ << " unsigned, forged or played-back PM_OUTPUT messages ignored\n";
  }
  out << "\n";
  snprintf(line, sizeof(line), "%-28s %-10s %-18s %-5s %-13s %7s %5s %5s %6s %8s\n", "COMMAND",
           "DEPUTY", "GROUP", "WANT", "STATE", "PID", "EXIT", "RESP", "CPU%", "RSS MB");
  out << line;
  for (const auto& c : commands_) {
    const DeputyView* d = FindDeputy(c->cfg.deputy);
    std::string state =
        c->reported ? ToString(static_cast<procman::CommandState>(c->status.state)) : "-";
    if (d->heard && DeputyLost(d->id, now_s)) state += "?";  // last known, deputy lost
    const char* want = !d->initialised ? "?" : c->desired_running ? "run" : "stop";
    if (c->reported) {
      snprintf(line, sizeof(line), "%-28s %-10s %-18s %-5s %-13s %7d %5d %5d %6.1f %8s\n",
               c->cfg.id.c_str(), c->cfg.deputy.c_str(), c->cfg.group.c_str(), want, state.c_str(),
               c->status.pid, c->status.exit_code, c->status.restart_count, c->status.cpu_percent,
               Mb(c->status.rss_bytes).c_str());
    } else {
      snprintf(line, sizeof(line), "%-28s %-10s %-18s %-5s %-13s\n", c->cfg.id.c_str(),
               c->cfg.deputy.c_str(), c->cfg.group.c_str(), want, state.c_str());
    }
    out << line;
  }
  return out.str();
}

std::string Sheriff::OutputTail(int lines, const std::string& command_id) const {
  std::vector<std::string> picked;
  for (auto it = tail_.rbegin(); it != tail_.rend() && static_cast<int>(picked.size()) < lines;
       ++it) {
    if (command_id.empty() || it->first == command_id)
      picked.push_back("[" + it->first + "] " + common::EscapeForLog(it->second, 4096));
  }
  std::string out;
  for (auto it = picked.rbegin(); it != picked.rend(); ++it) out += *it + "\n";
  return out;
}

// ---------------------------------------------------------------------------------------

std::string DescribeAction(const ScriptAction& a) {
  std::string s;
  switch (a.kind) {
    case ScriptAction::kStart:
      s = "start " + a.target.ToString();
      break;
    case ScriptAction::kStop:
      s = "stop " + a.target.ToString();
      break;
    case ScriptAction::kRestart:
      s = "restart " + a.target.ToString();
      break;
    case ScriptAction::kWaitMs:
      return "wait ms " + std::to_string(a.wait_ms);
    case ScriptAction::kWaitStatus:
      s = "wait " + a.target.ToString() + " status \"" + a.wait_status + "\"";
      break;
    case ScriptAction::kRunScript:
      return "run_script \"" + a.script + "\"";
  }
  if (a.kind != ScriptAction::kWaitStatus && !a.wait_status.empty())
    s += " wait \"" + a.wait_status + "\"";
  return s;
}

ScriptRunner::ScriptRunner(Sheriff* sheriff, const Script* script) : sheriff_(sheriff) {
  stack_.push_back({script, 0});
}

ScriptRunner::ScriptRunner(Sheriff* sheriff, ScriptAction action) : sheriff_(sheriff) {
  single_.name = "(command line)";
  single_.actions.push_back(action);
  stack_.push_back({&single_, 0});
}

std::string ScriptRunner::Describe() const {
  if (stack_.empty()) return "done";
  const Frame& f = stack_.back();
  if (f.index >= f.script->actions.size()) return "script \"" + f.script->name + "\" ending";
  return "script \"" + f.script->name + "\": " + DescribeAction(f.script->actions[f.index]);
}

ScriptRunner::Result ScriptRunner::Step(double now_s) {
  next_wakeup_s_ = std::numeric_limits<double>::infinity();
  while (!stack_.empty()) {
    Frame& f = stack_.back();
    if (f.index >= f.script->actions.size()) {
      stack_.pop_back();
      continue;
    }
    const ScriptAction& a = f.script->actions[f.index];
    if (!started_) {
      started_ = true;
      started_s_ = now_s;
      SARMAP_LOG(INFO) << (a.where.file.empty() ? "" : a.where.ToString() + ": ")
                       << DescribeAction(a);
      switch (a.kind) {
        case ScriptAction::kStart:
          sheriff_->Apply(Sheriff::Verb::kStart, a.target);
          break;
        case ScriptAction::kStop:
          sheriff_->Apply(Sheriff::Verb::kStop, a.target);
          break;
        case ScriptAction::kRestart:
          sheriff_->Apply(Sheriff::Verb::kRestart, a.target);
          break;
        case ScriptAction::kRunScript: {
          ++f.index;
          started_ = false;
          const Script* s = sheriff_->config().FindScript(a.script);
          stack_.push_back({s, 0});
          continue;
        }
        default:
          break;
      }
    }
    bool done = true;
    if (a.kind == ScriptAction::kWaitMs) {
      const double end = started_s_ + a.wait_ms / 1000.0;
      done = now_s >= end;
      if (!done) next_wakeup_s_ = end;
    } else if (!a.wait_status.empty()) {
      std::string why;
      done = sheriff_->Reached(a.target, a.wait_status, now_s, &why);
      std::string gone;
      if (!done && sheriff_->TargetDeputyGone(a.target, now_s, &gone)) {
        error_ = (a.where.file.empty() ? "" : a.where.ToString() + ": ") + DescribeAction(a) +
                 ": " + gone;
        return kFailed;
      }
      if (!done && now_s - started_s_ > a.timeout_s) {
        char buf[64];
        snprintf(buf, sizeof(buf), "%g", a.timeout_s);
        error_ = (a.where.file.empty() ? "" : a.where.ToString() + ": ") + DescribeAction(a) +
                 ": timed out after " + buf + " s: " + why;
        return kFailed;
      }
      if (!done) next_wakeup_s_ = std::min(now_s + 0.5, started_s_ + a.timeout_s + 0.01);
    }
    if (!done) return kRunning;
    ++f.index;
    started_ = false;
  }
  return kDone;
}

}  // namespace procman
}  // namespace sarmap
