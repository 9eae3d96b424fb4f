#include "common/node.h"

#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "common/lcm_guard.h"
#include "common/memory.h"
#include "common/signal_handlers.h"

namespace sarmap {
namespace common {
namespace {

// Self-pipe: the signal handler writes a byte, the main loop polls the read end.
int g_signal_pipe[2] = {-1, -1};
volatile sig_atomic_t g_signalled = 0;

void OnSignal(int) {
  g_signalled = 1;
  if (g_signal_pipe[1] >= 0) {
    const char byte = 1;
    ssize_t ignored = write(g_signal_pipe[1], &byte, 1);
    (void)ignored;
  }
}

void InstallSignalHandlers() {
  if (g_signal_pipe[0] >= 0) return;
  if (pipe(g_signal_pipe) != 0) throw std::runtime_error("pipe() failed");
  SetSignalHandler({SIGINT, SIGTERM}, OnSignal);
  signal(SIGPIPE, SIG_IGN);
}

std::string HostName() {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  return host;
}

}  // namespace

std::string DefaultLcmUrl() {
  for (const char* var : {"SARMAP_LCM_URL", "LCM_DEFAULT_URL"}) {
    const char* value = getenv(var);
    if (value && *value) return value;
  }
  return kDefaultLcmUrl;
}

Node::Node(const std::string& name, const std::string& lcm_url)
    : name_(name),
      lcm_url_(lcm_url.empty() ? DefaultLcmUrl() : lcm_url),
      lcm_(std::make_unique<lcm::LCM>(lcm_url_)),
      start_s_(SteadySeconds()),
      status_pub_(lcm_.get(), "NODE_STATUS", bus_auth_) {
  SetLogName(name);
  if (!lcm_->good()) {
    throw std::runtime_error("cannot initialise LCM on '" +
                             (lcm_url.empty() ? DefaultLcmUrl() : lcm_url) +
                             "' (is there a multicast route? see README, 'Networking')");
  }
  InstallSignalHandlers();
}

Node::Node(const std::string& name, const NodeArgs& args) : Node(name, args.lcm_url) {
  if (!args.bus_key_file.empty()) SetBusKey(LoadAuthKeyFile(args.bus_key_file));
}

Node::~Node() = default;

void Node::SetBusKey(AuthKey key) {
  *bus_auth_ = BusAuth(std::move(key));
  SARMAP_LOG(INFO) << "signed bus: publishing signed, accepting only messages signed with the bus key";
}

bool Node::stopping() const { return stop_ || g_signalled; }

void Node::GuardReceiveSocket() {
  receive_guarded_ = true;
  std::string error;
  const int guarded = GuardLcmReceiveSocket(lcm_.get(), lcm_url_, &error);
  if (guarded < 0) {
    SARMAP_LOG(WARN) << "no filter for hostile LCM fragments on the receive socket: " << error;
  }
}

void Node::AddTimer(double period_s, std::function<void()> callback) {
  timers_.push_back(Timer{period_s, Now() + period_s, std::move(callback)});
}

void Node::SetClock(std::function<double()> now_s) {
  const double uptime_s = Now() - start_s_;
  clock_ = std::move(now_s);
  const double now = Now();
  start_s_ = now - uptime_s;
  for (Timer& t : timers_) t.next_s = now + t.period_s;
}

bool Node::SpinOnce(double timeout_s) {
  if (stopping()) return false;
  double now = Now();
  double wait_s = timeout_s;
  for (const auto& t : timers_) wait_s = std::min(wait_s, std::max(0.0, t.next_s - now));
  pollfd fds[2] = {{lcm_->getFileno(), POLLIN, 0}, {g_signal_pipe[0], POLLIN, 0}};
  const int ready = poll(fds, 2, static_cast<int>(wait_s * 1000.0 + 0.5));
  if (ready < 0 && errno != EINTR) {
    SARMAP_LOG(ERROR) << "poll failed: " << strerror(errno);
    return false;
  }
  if (ready > 0 && (fds[0].revents & POLLIN)) {
    if (lcm_->handle() != 0) {
      SARMAP_LOG(ERROR) << "LCM handle() failed";
      return false;
    }
  }
  now = Now();
  for (auto& t : timers_) {
    if (now >= t.next_s) {
      // Skip missed periods instead of bursting after a stall.
      t.next_s = std::max(t.next_s + t.period_s, now);
      try {
        t.callback();
      } catch (const std::exception& e) {
        SARMAP_LOG(ERROR) << "timer callback failed: " << e.what();
      }
    }
  }
  return !stopping();
}

int Node::Run() {
  AddTimer(1.0, [this] { PublishStatus(); });
  // A node that runs for hours holds what it uses, not the pages of its largest burst.
  AddTimer(kReleaseFreeMemoryPeriod_s, [] { ReleaseFreeMemory(); });
  SARMAP_LOG(INFO) << "running (pid " << getpid() << ")";
  while (SpinOnce(0.5)) {
  }
  PublishStatus();
  SARMAP_LOG(INFO) << "stopped; " << total_dropped() << " malformed messages dropped";
  return 0;
}

int64_t Node::total_dropped() const {
  int64_t total = 0;
  for (const auto& [channel, s] : stats_) total += s.dropped_malformed;
  return total;
}

std::string PublisherOf(const sarmap::slam_anchor_request_t& msg) { return msg.client_id; }

std::string PublisherOf(const sarmap::node_status_t& msg) {
  return msg.node_name + "@" + msg.host + ":" + std::to_string(msg.pid);
}

std::string PublisherOf(const sarmap::pm_info_t& msg) { return msg.deputy_id + "@" + msg.host; }

std::string PublisherOf(const sarmap::pm_output_t& msg) { return msg.deputy_id; }

void Node::PublishStatus() {
  if (status_channel_.empty()) return;
  sarmap::node_status_t status{};
  status.header.utime = WallClockUtime();
  status.header.frame = "";
  status.node_name = name_;
  status.host = HostName();
  status.pid = getpid();
  status.uptime_us = static_cast<int64_t>((Now() - start_s_) * 1e6);
  for (const auto& [channel, s] : stats_) {
    sarmap::channel_stats_t c;
    c.channel = channel;
    c.type_name = s.type_name;
    c.received = s.received;
    c.dropped_malformed = s.dropped_malformed;
    c.handler_errors = s.handler_errors;
    c.sequence_gaps = s.sequence.gaps();
    c.reordered = s.sequence.reordered();
    c.last_utime = s.last_utime;
    status.channels.push_back(c);
  }
  status.num_channels = static_cast<int32_t>(status.channels.size());
  status.message = status_message_;
  if (status_channel_ != status_pub_.channel()) status_pub_ = Advertise<sarmap::node_status_t>(status_channel_);
  status_pub_.Publish(&status);
}

void Node::Dropped(const std::string& channel, ChannelStats* stats, const std::string& why) {
  ++stats->dropped_malformed;
  long suppressed = 0;
  auto it = drop_log_limit_.try_emplace(channel, 1.0).first;
  if (it->second.Allow(SteadySeconds(), &suppressed)) {
    // Channel names, decode errors and handler errors can quote what a sender put on the bus.
    SARMAP_LOG(WARN) << "dropped a message on " << EscapeForLog(channel) << ": "
                     << EscapeForLog(why, 512) << " (dropped so far: " << stats->dropped_malformed
                     << (suppressed ? ", " + std::to_string(suppressed) + " not logged" : "")
                     << ")";
  }
}

void Node::HandlerError(const std::string& channel, ChannelStats* stats, const std::string& what) {
  ++stats->handler_errors;
  long suppressed = 0;
  auto it = drop_log_limit_.try_emplace("handler:" + channel, 1.0).first;
  if (it->second.Allow(SteadySeconds(), &suppressed)) {
    SARMAP_LOG(ERROR) << "handler for " << EscapeForLog(channel)
                      << " failed: " << EscapeForLog(what, 512)
                      << " (errors so far: " << stats->handler_errors << ")";
  }
}

}  // namespace common
}  // namespace sarmap
