#include "procman/deputy.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "common/decode.h"
#include "common/time.h"
#include "sarmap/node_status_t.hpp"
#include "sarmap/pm_output_t.hpp"

namespace sarmap {
namespace procman {
namespace {

std::string HostName() {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  return host;
}

RespawnPolicy PolicyFrom(const ProcmanOptions& o) {
  RespawnPolicy p;
  p.base_s = o.respawn_base_s;
  p.max_s = o.respawn_max_s;
  p.stable_run_s = o.respawn_stable_run_s;
  return p;
}

}  // namespace

std::string DeputyStatePath(const std::string& state_dir, const std::string& id) {
  std::string dir = state_dir;
  if (dir.empty()) {
    const char* xdg = getenv("XDG_STATE_HOME");
    const char* home = getenv("HOME");
    dir = (xdg && *xdg) ? std::string(xdg) + "/sarmap"
                        : std::string(home && *home ? home : "/tmp") + "/.local/state/sarmap";
  }
  // Create it (and parents) if needed.
  for (size_t pos = 1; pos != std::string::npos; pos = dir.find('/', pos + 1)) {
    mkdir(dir.substr(0, pos).c_str(), 0700);
  }
  mkdir(dir.c_str(), 0700);
  std::string safe_id = id;
  for (auto& c : safe_id) {
    if (!isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  }
  return dir + "/procman-deputy-" + safe_id + ".counters";
}

void PutOwnDirectoryOnPath() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) return;
  self[n] = '\0';
  std::string dir(self);
  dir = dir.substr(0, dir.rfind('/'));
  const char* path = getenv("PATH");
  setenv("PATH", (dir + ":" + (path ? path : "/usr/local/bin:/usr/bin:/bin")).c_str(), 1);
}

Deputy::Deputy(lcm::LCM* lcm, const ProcmanOptions& options, std::string id, Key key,
               const std::string& replay_state_path)
    : lcm_(lcm),
      options_(options),
      id_(std::move(id)),
      host_(HostName()),
      key_(std::move(key)),
      replay_(replay_state_path),
      supervisor_(PolicyFrom(options), static_cast<size_t>(options.output_buffer_bytes)) {
  start_s_ = Now();
  subscription_ = lcm_->subscribe("^" + options_.orders_channel + "$", &Deputy::OnOrders, this);
  machine_.Update();
  SARMAP_LOG(INFO) << "deputy '" << id_ << "' on " << host_ << " (pid " << getpid()
                   << "), orders on " << options_.orders_channel << ", replay state "
                   << (replay_state_path.empty() ? "(memory only)" : replay_state_path);
}

Deputy::~Deputy() {
  if (subscription_) lcm_->unsubscribe(subscription_);
}

void Deputy::OnOrders(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  sarmap::pm_orders_t orders;
  std::string problem;
  if (!common::DecodeMessage(rbuf->data, rbuf->data_size, &orders, &problem)) {
    ++malformed_;
    long suppressed = 0;
    if (refuse_log_limit_.try_emplace("malformed", 5.0).first->second.Allow(Now(), &suppressed)) {
      SARMAP_LOG(WARN) << "dropped a message on " << channel << ": " << problem << " (so far "
                       << malformed_ << ")";
    }
    return;
  }
  if (orders.deputy_id == kProbeDeputyId && orders.num_commands == 0) {
    // A sheriff starting up asks every deputy to report now rather than within a second.
    // Orders nothing, so it needs no signature; rate-limited.
    const double now = Now();
    if (now - last_probe_reply_s_ >= 0.05) {
      last_probe_reply_s_ = now;
      info_dirty_ = true;
    }
    return;
  }
  if (orders.deputy_id != id_) return;  // for another deputy
  ++orders_received_;
  if (shutting_down_) return;
  bool persisted = true;
  const Verdict verdict = VerifyOrders(key_, orders, &replay_, &persisted);
  if (verdict != Verdict::kAccepted) {
    ++refused_;
    info_dirty_ = true;
    long suppressed = 0;
    if (refuse_log_limit_.try_emplace(ToString(verdict), 1.0)
            .first->second.Allow(Now(), &suppressed)) {
      SARMAP_LOG(WARN) << "REFUSED orders claiming sheriff '" << orders.sheriff_id << "', counter "
                       << orders.counter << ": " << ToString(verdict)
                       << "; nothing changed (refused so far: " << refused_
                       << (suppressed ? ", " + std::to_string(suppressed) + " not logged" : "")
                       << ")";
    }
    return;
  }
  if (!persisted && refuse_log_limit_.try_emplace("persist", 30.0).first->second.Allow(Now())) {
    SARMAP_LOG(ERROR) << "cannot write replay state " << replay_.state_path()
                      << "; a deputy restart could accept replays of these orders";
  }
  if (orders.counter != last_order_counter_) info_dirty_ = true;
  last_order_counter_ = orders.counter;
  std::vector<CommandSpec> specs;
  for (const auto& c : orders.commands) {
    CommandSpec s;
    s.id = c.command_id;
    s.group = c.group;
    s.exec = c.exec;
    s.use_shell = c.use_shell;
    s.auto_respawn = c.auto_respawn;
    s.stop_signal = c.stop_signal;
    s.stop_time_allowed_s = c.stop_time_allowed_s;
    s.desired_running = c.desired_running;
    s.desired_runid = c.desired_runid;
    // Run ids version each command's desired state: a re-send from another sheriff that has
    // not yet seen the latest change must not undo it.
    const CommandSpec* current = supervisor_.FindSpec(s.id);
    if (current && current->desired_runid > s.desired_runid) {
      s.desired_running = current->desired_running;
      s.desired_runid = current->desired_runid;
    }
    specs.push_back(s);
  }
  supervisor_.SetDesired(specs);
  // Act (and report) at once rather than at the next wake-up.
  if (supervisor_.Step(Now())) info_dirty_ = true;
}

void Deputy::Shutdown() {
  if (shutting_down_) return;
  shutting_down_ = true;
  SARMAP_LOG(INFO) << "stopping all commands";
  supervisor_.Shutdown();
}

void Deputy::AddFds(std::vector<pollfd>* fds) {
  for (int fd : supervisor_.OutputFds()) fds->push_back({fd, POLLIN, 0});
}

double Deputy::NextWakeup() const {
  double next = std::min(next_info_s_, supervisor_.NextWakeup());
  if (info_dirty_) next = 0;
  return next;
}

void Deputy::OnWake(const std::vector<pollfd>& /*fds*/, double now_s) {
  // Cheap enough to run on every wake-up: a reap, non-blocking reads and a state check.
  if (supervisor_.Step(now_s)) info_dirty_ = true;
  if (now_s >= next_output_s_) {
    PublishOutput();
    next_output_s_ = now_s + options_.output_period_s;
  }
  if (now_s >= next_info_s_) {
    supervisor_.UpdateUsage(now_s);
    machine_.Update();
    PublishNodeStatus(now_s);
    info_dirty_ = true;
  }
  if (info_dirty_) PublishInfo(now_s);
}

void Deputy::PublishInfo(double now_s) {
  sarmap::pm_info_t info;
  info.header.utime = common::WallClockUtime();
  info.header.seq = info_seq_++;
  info.header.frame = "";
  info.deputy_id = id_;
  info.host = host_;
  info.cpu_load = machine_.cpu_load();
  info.phys_mem_total_bytes = machine_.mem_total_bytes();
  info.phys_mem_free_bytes = machine_.mem_free_bytes();
  info.last_order_counter = last_order_counter_;
  info.refused_orders = refused_;
  for (const auto& s : supervisor_.Status()) {
    sarmap::pm_command_status_t c;
    c.command_id = s.id;
    c.group = s.group;
    c.exec = s.exec;
    c.state = static_cast<int8_t>(s.state);
    c.pid = s.pid;
    c.exit_code = s.exit_code;
    c.restart_count = s.restart_count;
    c.actual_runid = s.actual_runid;
    c.cpu_percent = static_cast<float>(s.cpu_percent);
    c.rss_bytes = s.rss_bytes;
    c.auto_respawn = s.auto_respawn;
    info.commands.push_back(c);
  }
  info.num_commands = static_cast<int32_t>(info.commands.size());
  lcm_->publish(options_.info_channel, &info);
  info_dirty_ = false;
  next_info_s_ = now_s + options_.info_period_s;
}

void Deputy::PublishNodeStatus(double now_s) {
  sarmap::node_status_t status;
  status.header.utime = common::WallClockUtime();
  status.header.seq = status_seq_++;
  status.header.frame = "";
  status.node_name = "sarmap-procman-deputy[" + id_ + "]";
  status.host = host_;
  status.pid = getpid();
  status.uptime_us = static_cast<int64_t>((now_s - start_s_) * 1e6);
  sarmap::channel_stats_t orders;
  orders.channel = options_.orders_channel;
  orders.type_name = sarmap::pm_orders_t::getTypeName();
  orders.received = orders_received_ - refused_;
  orders.dropped_malformed = malformed_ + refused_;
  orders.handler_errors = 0;
  orders.sequence_gaps = 0;
  orders.reordered = 0;
  orders.last_utime = 0;
  status.channels.push_back(orders);
  status.num_channels = 1;
  int running = 0;
  const auto all = supervisor_.Status();
  for (const auto& c : all) running += c.state == CommandState::kRunning;
  status.message = std::to_string(running) + "/" + std::to_string(all.size()) +
                   " commands running, " + std::to_string(refused_) + " orders refused";
  lcm_->publish("NODE_STATUS", &status);
}

void Deputy::PublishOutput() {
  auto chunks = supervisor_.TakeOutput(static_cast<size_t>(options_.output_max_bytes));
  if (chunks.empty()) return;
  sarmap::pm_output_t out;
  out.header.utime = common::WallClockUtime();
  out.header.seq = output_seq_++;
  out.header.frame = "";
  out.deputy_id = id_;
  for (auto& [cmd, text] : chunks) {
    out.command_ids.push_back(cmd);
    // LCM strings end at their first NUL: a child printing one would make an encoding that
    // every receiver rejects (and publish uninitialised bytes after it).
    std::replace(text.begin(), text.end(), '\0', '?');
    out.text.push_back(std::move(text));
  }
  out.num_commands = static_cast<int32_t>(out.command_ids.size());
  lcm_->publish(options_.output_channel, &out);
}

}  // namespace procman
}  // namespace sarmap
