#include "procman/event_loop.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "common/logging.h"
#include "common/signal_handlers.h"

namespace sarmap {
namespace procman {
namespace {

int g_wake_pipe[2] = {-1, -1};
volatile sig_atomic_t g_interrupts = 0;

void OnSignal(int sig) {
  const int saved = errno;
  if (sig == SIGINT || sig == SIGTERM) g_interrupts = g_interrupts + 1;
  const char byte = 1;
  ssize_t ignored = write(g_wake_pipe[1], &byte, 1);
  (void)ignored;
  errno = saved;
}

void InstallHandlers() {
  if (g_wake_pipe[0] >= 0) return;
  if (pipe2(g_wake_pipe, O_CLOEXEC | O_NONBLOCK) != 0) throw std::runtime_error("pipe2 failed");
  common::SetSignalHandler({SIGCHLD, SIGINT, SIGTERM}, OnSignal, SA_RESTART | SA_NOCLDSTOP);
  signal(SIGPIPE, SIG_IGN);
}

}  // namespace

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

EventLoop::EventLoop(lcm::LCM* lcm) : lcm_(lcm) { InstallHandlers(); }

int EventLoop::Interrupts() { return g_interrupts; }

bool EventLoop::RunOnce(double max_wait_s) {
  double now = Now();
  double wait_s = max_wait_s;
  for (auto* p : participants_) wait_s = std::min(wait_s, p->NextWakeup() - now);
  wait_s = std::max(0.0, wait_s);
  std::vector<pollfd> fds = {{g_wake_pipe[0], POLLIN, 0}, {lcm_->getFileno(), POLLIN, 0}};
  for (auto* p : participants_) p->AddFds(&fds);
  const int ready = poll(fds.data(), fds.size(), static_cast<int>(std::ceil(wait_s * 1000.0)));
  if (ready < 0 && errno != EINTR) {
    SARMAP_LOG(ERROR) << "poll failed: " << strerror(errno);
    return false;
  }
  if (ready > 0 && (fds[0].revents & POLLIN)) {
    char buf[64];
    while (read(g_wake_pipe[0], buf, sizeof(buf)) > 0) {
    }
  }
  if (ready > 0 && (fds[1].revents & POLLIN)) {
    // Drain what is queued, without blocking.
    for (int i = 0; i < 100; ++i) {
      if (lcm_->handleTimeout(0) <= 0) break;
    }
  }
  now = Now();
  for (auto* p : participants_) p->OnWake(fds, now);
  return true;
}

}  // namespace procman
}  // namespace sarmap
