#pragma once
// Orders built by hand for the procman tests (as a sheriff, or as an attacker, would send
// them). Header-only, test code only.

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <string>

#include "sarmap/pm_orders_t.hpp"

namespace sarmap {
namespace procman {
namespace testing_util {

// Unsigned orders (an all-zero HMAC), stamped `counter` us, from `sheriff_id` to `deputy_id`
// (deputy_session 0): run `command_id` (`exec`, no group) once, respawned, stopped with SIGINT.
inline sarmap::pm_orders_t OrdersToRun(const std::string& sheriff_id, const std::string& deputy_id,
                                       const std::string& command_id, const std::string& exec,
                                       int64_t counter) {
  sarmap::pm_orders_t o;
  o.header.utime = counter;
  o.header.seq = 0;
  o.header.frame = "";
  o.sheriff_id = sheriff_id;
  o.deputy_id = deputy_id;
  o.deputy_session = 0;
  o.counter = counter;
  sarmap::pm_command_order_t c;
  c.command_id = command_id;
  c.group = "";
  c.exec = exec;
  c.use_shell = false;
  c.auto_respawn = true;
  c.stop_signal = 2;
  c.stop_time_allowed_s = 1;
  c.desired_running = true;
  c.desired_runid = 1;
  o.commands.push_back(c);
  o.num_commands = 1;
  std::fill(std::begin(o.hmac_sha256), std::end(o.hmac_sha256), 0);
  return o;
}

}  // namespace testing_util
}  // namespace procman
}  // namespace sarmap
