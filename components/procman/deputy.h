#pragma once
// The deputy: obeys verified orders (PM_ORDERS) for its id, runs its commands through a
// Supervisor, and reports PM_INFO (1 Hz and on every change) and PM_OUTPUT (rate-limited).
// Orders that are unsigned, forged or replayed are refused, logged and counted; nothing is
// ever run that a verified sheriff did not order. The last verified orders stay in force
// when the sheriff goes away.

#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>

#include "common/bus_auth.h"
#include "common/logging.h"
#include "procman/event_loop.h"
#include "procman/order_auth.h"
#include "procman/process_table.h"
#include "procman/procman_options.h"
#include "procman/supervisor.h"
#include "sarmap/pm_info_t.hpp"
#include "sarmap/pm_orders_t.hpp"

namespace sarmap {
namespace procman {

class Deputy : public EventLoop::Participant {
 public:
  // Starts a new session (a random number announced in every signed PM_INFO): orders
  // signed for an earlier run of this deputy are refused. Commands start with `environment`
  // (the launchers pass InheritedEnvironment(OwnDirectory()): .pmd files name sarmap programs
  // without paths).
  Deputy(lcm::LCM* lcm, const ProcmanOptions& options, std::string id, Key key,
         Environment environment = InheritedEnvironment());
  ~Deputy() override;

  void AddFds(std::vector<pollfd>* fds) override;
  void OnWake(const std::vector<pollfd>& fds, double now_s) override;
  double NextWakeup() const override;

  // Stops every command (SIGINT/SIGTERM of the deputy); Finished() once all are down.
  void Shutdown();
  bool Finished() const { return shutting_down_ && supervisor_.AllStopped(); }

  const std::string& id() const { return id_; }
  // With a bus key (common/bus_auth.h), PM_INFO, PM_OUTPUT and NODE_STATUS also carry the bus
  // signature, so nodes on a signed bus (the viewer) hear the deputy.
  void SetBusKey(common::AuthKey key) { bus_auth_ = common::BusAuth(std::move(key)); }
  int64_t session() const { return replay_.session(); }
  // Microseconds since this deputy (its session) started, on the monotonic clock: the clock
  // that order counters are checked against.
  int64_t SessionClockUs() const;
  int refused_orders() const { return refused_; }
  // Messages on the orders channel that did not decode (common::DecodeMessage).
  int malformed_orders() const { return malformed_; }

 private:
  void OnOrders(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void PublishInfo(double now_s);
  void PublishOutput();
  // NODE_STATUS like every sarmap node (health for the viewer), with the info period.
  void PublishNodeStatus(double now_s);

  lcm::LCM* lcm_;
  ProcmanOptions options_;
  std::string id_;
  std::string host_;
  Key key_;
  common::BusAuth bus_auth_;
  ReplayGuard replay_;
  Supervisor supervisor_;
  MachineUsage machine_;
  lcm::Subscription* subscription_ = nullptr;
  int64_t last_order_counter_ = -1;
  int refused_ = 0;
  int malformed_ = 0;
  bool shutting_down_ = false;
  bool info_dirty_ = true;
  double next_info_s_ = 0;
  double next_output_s_ = 0;
  int64_t info_seq_ = 0, output_seq_ = 0, status_seq_ = 0;
  int64_t orders_received_ = 0;
  double start_s_ = 0;
  double last_probe_reply_s_ = -1e9;
  bool probe_pending_ = false;
  int64_t probe_echo_ = 0;
  int64_t last_info_clock_us_ = 0;
  int64_t last_output_clock_us_ = 0;
  int64_t start_us_ = 0;  // steady clock, microseconds
  std::map<std::string, common::RateLimiter> refuse_log_limit_;
};

}  // namespace procman
}  // namespace sarmap
