#include "procman/deputy.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>

#include "common/bus_publish.h"
#include "common/decode.h"
#include "common/logging.h"
#include "procman/launcher_header.h"
#include "sarmap/node_status_t.hpp"
#include "sarmap/pm_output_t.hpp"

namespace sarmap {
namespace procman {
namespace {

// Probes are answered at most this often (a flood of probes costs at most 20 reports/s).
constexpr double kProbeReplyPeriodS = 0.05;

int64_t SteadyMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

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

Deputy::Deputy(lcm::LCM* lcm, const ProcmanOptions& options, std::string id, Key key,
               Environment environment)
    : lcm_(lcm),
      options_(options),
      id_(std::move(id)),
      host_(HostName()),
      key_(std::move(key)),
      replay_(RandomNonce(), static_cast<int64_t>(options.order_window_s * 1e6)),
      supervisor_(PolicyFrom(options), static_cast<size_t>(options.output_buffer_bytes),
                  std::move(environment)) {
  start_s_ = Now();
  start_us_ = SteadyMicros();
  subscription_ = lcm_->subscribe("^" + options_.orders_channel + "$", &Deputy::OnOrders, this);
  machine_.Update();
  SARMAP_LOG(INFO) << "deputy '" << id_ << "' on " << host_ << " (pid " << getpid()
                   << "), orders on " << options_.orders_channel << ", session "
                   << replay_.session();
}

int64_t Deputy::SessionClockUs() const { return SteadyMicros() - start_us_; }

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
      SARMAP_LOG(WARN) << "dropped a message on " << common::EscapeForLog(channel) << ": "
                       << common::EscapeForLog(problem, 512) << " (so far " << malformed_ << ")";
    }
    return;
  }
  if (orders.deputy_id == kProbeDeputyId && orders.num_commands == 0) {
    // A sheriff asks every deputy to report now rather than within a second. A signed probe
    // carries a nonce to echo: the sheriff's proof that the report is live. Unsigned probes
    // (observers) get an answer too, without an echo. At most 20 answers a second.
    if (!IsUnsigned(orders.hmac_sha256) && SignatureValid(key_, orders)) {
      probe_echo_ = orders.counter;
    }
    probe_pending_ = true;
    return;
  }
  if (orders.deputy_id != id_) return;  // for another deputy
  ++orders_received_;
  if (shutting_down_) return;
  const Verdict verdict = VerifyOrders(key_, orders, &replay_, SessionClockUs());
  if (verdict != Verdict::kAccepted) {
    ++refused_;
    info_dirty_ = true;
    long suppressed = 0;
    if (refuse_log_limit_.try_emplace(ToString(verdict), 1.0)
            .first->second.Allow(Now(), &suppressed)) {
      SARMAP_LOG(WARN) << "REFUSED orders claiming sheriff '"
                       << common::EscapeForLog(orders.sheriff_id) << "', counter " << orders.counter
                       << ": " << ToString(verdict)
                       << "; nothing changed (refused so far: " << refused_
                       << (suppressed ? ", " + std::to_string(suppressed) + " not logged" : "")
                       << ")";
    }
    return;
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
  if (probe_pending_) next = std::min(next, last_probe_reply_s_ + kProbeReplyPeriodS);
  if (info_dirty_) next = 0;
  return next;
}

void Deputy::OnWake(const std::vector<pollfd>& /*fds*/, double now_s) {
  // Cheap enough to run on every wake-up: a reap, non-blocking reads and a state check.
  if (supervisor_.Step(now_s)) info_dirty_ = true;
  if (probe_pending_ && now_s >= last_probe_reply_s_ + kProbeReplyPeriodS) {
    probe_pending_ = false;
    last_probe_reply_s_ = now_s;
    info_dirty_ = true;
  }
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
  info.header = LauncherHeader(&info_seq_);
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
  info.session = replay_.session();
  // Strictly increasing, so that the sheriff can tell every report from a played-back one.
  last_info_clock_us_ = std::max(last_info_clock_us_ + 1, SessionClockUs());
  info.session_clock_us = last_info_clock_us_;
  info.probe_echo = probe_echo_;
  std::fill(std::begin(info.hmac_sha256), std::end(info.hmac_sha256), 0);
  try {
    SignInfo(key_, &info);
  } catch (const std::runtime_error& e) {
    // Cannot happen with decoded orders (no NUL bytes); never publish unsigned state.
    SARMAP_LOG(ERROR) << e.what();
    return;
  }
  common::PublishOnBus(lcm_, &bus_auth_, options_.info_channel, info);
  info_dirty_ = false;
  next_info_s_ = now_s + options_.info_period_s;
}

void Deputy::PublishNodeStatus(double now_s) {
  sarmap::node_status_t status;
  status.header = LauncherHeader(&status_seq_);
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
  common::PublishOnBus(lcm_, &bus_auth_, "NODE_STATUS", status);
}

void Deputy::PublishOutput() {
  auto chunks = supervisor_.TakeOutput(static_cast<size_t>(options_.output_max_bytes));
  if (chunks.empty()) return;
  sarmap::pm_output_t out;
  out.header = LauncherHeader(&output_seq_);
  out.deputy_id = id_;
  for (auto& [cmd, text] : chunks) {
    out.command_ids.push_back(cmd);
    // LCM strings end at their first NUL: a child printing one would make an encoding that
    // every receiver rejects (and publish uninitialised bytes after it).
    std::replace(text.begin(), text.end(), '\0', '?');
    out.text.push_back(std::move(text));
  }
  out.num_commands = static_cast<int32_t>(out.command_ids.size());
  // Signed and tied to this session like PM_INFO, so that no one else can put lines into the
  // sheriff's view of a command; its own clock, strictly increasing, against playback.
  out.session = replay_.session();
  last_output_clock_us_ = std::max(last_output_clock_us_ + 1, SessionClockUs());
  out.session_clock_us = last_output_clock_us_;
  std::fill(std::begin(out.hmac_sha256), std::end(out.hmac_sha256), 0);
  try {
    SignOutput(key_, &out);
  } catch (const std::runtime_error& e) {
    SARMAP_LOG(ERROR) << e.what();  // cannot happen: NUL bytes are replaced above
    return;
  }
  common::PublishOnBus(lcm_, &bus_auth_, options_.output_channel, out);
}

}  // namespace procman
}  // namespace sarmap
