#pragma once
// The main loop shared by sheriff and deputy (and both in one process, --lone-ranger):
// waits on LCM, command output pipes, stdin and a self-pipe that SIGCHLD, SIGINT and SIGTERM
// write to, so nothing polls on a fixed tick while idle.

#include <poll.h>

#include <lcm/lcm-cpp.hpp>
#include <vector>

namespace sarmap {
namespace procman {

class EventLoop {
 public:
  class Participant {
   public:
    virtual ~Participant() = default;
    // Extra file descriptors to wait on.
    virtual void AddFds(std::vector<pollfd>* /*fds*/) {}
    // Called after every wake-up (any fd, signal or timeout), with the poll results.
    virtual void OnWake(const std::vector<pollfd>& fds, double now_s) = 0;
    // Steady-clock time of the next thing to do (+inf: nothing).
    virtual double NextWakeup() const = 0;
  };

  // Installs the signal handlers (once per process).
  explicit EventLoop(lcm::LCM* lcm);
  void Add(Participant* p) { participants_.push_back(p); }
  // Waits at most `max_wait_s`, handles what is ready. False when LCM failed.
  bool RunOnce(double max_wait_s = 1.0);
  // SIGINT or SIGTERM arrived (count); the program decides how to wind down.
  static int Interrupts();

 private:
  lcm::LCM* lcm_;
  std::vector<Participant*> participants_;
};

double Now();  // steady clock, seconds

}  // namespace procman
}  // namespace sarmap
