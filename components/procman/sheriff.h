#pragma once
// The sheriff: holds the desired state of every command in a .pmd config, sends it signed to
// each deputy (on every change and re-sent every resend_period_s), and tracks what the
// deputies report.
//
// A sheriff never disturbs what runs: it adopts each deputy's current state from its first
// PM_INFO before it sends that deputy anything, so a restarted sheriff (or a one-shot
// `sarmap-procman ... status`) changes nothing. It also adopts the desired state from
// verified orders of other sheriffs (so a one-shot command and a live sheriff agree).
//
// With a key, it acts only on signed, live PM_INFO (see order_auth.h): unsigned, forged
// and played-back reports are ignored and counted, so no one without the key can make a
// script wait end. A deputy silent for deputy_gone_after_s fails the script step waiting
// on it.

#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/bus_auth.h"
#include "common/logging.h"
#include "procman/event_loop.h"
#include "procman/order_auth.h"
#include "procman/pmd_config.h"
#include "procman/procman_options.h"
#include "sarmap/pm_info_t.hpp"
#include "sarmap/pm_orders_t.hpp"
#include "sarmap/pm_output_t.hpp"

namespace sarmap {
namespace procman {

class Sheriff : public EventLoop::Participant {
 public:
  enum class Verb { kStart, kStop, kRestart };

  // key == nullptr: observer (sends nothing, verifies nothing).
  Sheriff(lcm::LCM* lcm, const ProcmanOptions& options, Config config, const Key* key,
          std::string sheriff_id);
  ~Sheriff() override;
  // With a bus key (common/bus_auth.h), orders also carry the bus signature.
  void SetBusKey(common::AuthKey key) { bus_auth_ = common::BusAuth(std::move(key)); }

  // Changes the desired state of the target's commands. Commands of a deputy not heard yet
  // get the change once it is heard.
  void Apply(Verb verb, const Target& target);
  // True when every command of the target is in `status` ("running" or "stopped") on a
  // deputy that is present and has acknowledged the latest orders; otherwise `why_not`
  // says what is missing.
  bool Reached(const Target& target, const std::string& status, double now_s,
               std::string* why_not) const;

  // True when every change was sent to its deputy and acknowledged (a one-shot command exits
  // only then); otherwise `why_not` names what is still awaited.
  bool Settled(std::string* why_not) const;
  bool AllDeputiesHeard() const;
  bool DeputyLost(const std::string& deputy_id, double now_s) const;
  bool DeputyHeard(const std::string& deputy_id) const;
  // Heard once, then silent for deputy_gone_after_s: killed, crashed or cut off.
  bool DeputyGone(const std::string& deputy_id, double now_s) const;
  // True when a deputy of the target's commands is gone; `why` names it.
  bool TargetDeputyGone(const Target& target, double now_s, std::string* why) const;
  // When the next deputy that is present now would count as lost (+inf: none).
  double NextLostDeadline(double now_s) const;
  int RefusedOrders(const std::string& deputy_id) const;
  // Messages on the procman channels that did not decode (common::DecodeMessage); each is
  // dropped and logged (rate-limited per channel).
  int malformed_messages() const { return malformed_; }
  // PM_INFO reports ignored: unsigned or forged (with a key), or played back (stale).
  int ignored_info() const { return ignored_info_; }
  // PM_OUTPUT messages ignored (with a key): unsigned, forged, of another session or played
  // back. Without a key (an observer) output is shown unverified.
  int ignored_output() const { return ignored_output_; }
  // State of a command as last reported (-1: not reported).
  int CommandState(const std::string& command_id) const;
  int CommandPid(const std::string& command_id) const;

  std::string Table(double now_s) const;
  std::string OutputTail(int lines, const std::string& command_id = "") const;
  const Config& config() const { return config_; }
  bool observer() const { return key_ == nullptr; }

  void OnWake(const std::vector<pollfd>& fds, double now_s) override;
  double NextWakeup() const override;

 private:
  struct CommandView;
  struct DeputyView;
  void OnInfo(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void OnOutput(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void OnOrders(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  template <class T>
  bool Decode(const lcm::ReceiveBuffer* rbuf, const std::string& channel, T* msg);
  void Adopt(DeputyView* d);
  void ApplyTo(Verb verb, CommandView* c, DeputyView* d);
  bool Acknowledged(const DeputyView& d) const;
  void SendOrders(DeputyView* d, double now_s);
  // The deputy's session clock now, from its last verified report.
  int64_t EstimatedDeputyClockUs(const DeputyView& d, double now_s) const;
  DeputyView* FindDeputy(const std::string& id);
  const DeputyView* FindDeputy(const std::string& id) const;
  const CommandView* FindCommand(const std::string& id) const;

  lcm::LCM* lcm_;
  common::BusAuth bus_auth_;
  ProcmanOptions options_;
  Config config_;
  const Key* key_;
  std::string sheriff_id_;
  InfoGuard info_guard_;
  std::vector<std::unique_ptr<CommandView>> commands_;
  std::vector<std::unique_ptr<DeputyView>> deputies_;
  std::vector<lcm::Subscription*> subscriptions_;
  std::deque<std::pair<std::string, std::string>> tail_;  // (command, line)
  void SendProbe();
  double last_probe_s_ = -1e9;
  int ignored_info_ = 0;
  int ignored_output_ = 0;
  double next_resend_s_ = 0;
  double next_probe_s_ = 0;
  int probes_sent_ = 0;
  int64_t orders_seq_ = 0;
  int malformed_ = 0;
  std::map<std::string, common::RateLimiter> drop_log_limit_;
};

// Runs a script (or a single action) against a sheriff, one step per wake-up.
class ScriptRunner {
 public:
  enum Result { kRunning, kDone, kFailed };
  ScriptRunner(Sheriff* sheriff, const Script* script);
  // A one-action script (one-shot start/stop/restart).
  ScriptRunner(Sheriff* sheriff, ScriptAction action);
  Result Step(double now_s);
  double NextWakeup() const { return next_wakeup_s_; }
  const std::string& error() const { return error_; }
  std::string Describe() const;  // the action under way

 private:
  struct Frame {
    const Script* script;
    size_t index;
  };
  Sheriff* sheriff_;
  Script single_;
  std::vector<Frame> stack_;
  bool started_ = false;
  double started_s_ = 0;
  double next_wakeup_s_ = 0;
  std::string error_;
};

std::string DescribeAction(const ScriptAction& a);

}  // namespace procman
}  // namespace sarmap
