#pragma once
// SetSignalHandler(): one sigaction set-up for the processes that stop on SIGINT and SIGTERM
// (nodes, the launcher, the log recorder and echo).
#include <signal.h>

#include <cstring>
#include <initializer_list>

namespace sarmap {
namespace common {

// Calls `handler` on each of `signals`, with no signal blocked while it runs and sigaction's
// `flags` (e.g. SA_RESTART).
inline void SetSignalHandler(std::initializer_list<int> signals, void (*handler)(int),
                             int flags = 0) {
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = handler;
  sigemptyset(&action.sa_mask);
  action.sa_flags = flags;
  for (const int signal_number : signals) sigaction(signal_number, &action, nullptr);
}

}  // namespace common
}  // namespace sarmap
