#pragma once
// sarmap-teleop's core: what the operator asks for (an emergency stop, its release, a drive),
// as the TELEOP messages that carry it and when each goes out. No LCM runtime; signing is
// common/command_auth's (teleop_sender.h).

#include <cstdint>
#include <string>
#include <vector>

#include "common/options.h"

namespace sarmap {
namespace teleop {

struct TeleopOptions {
  std::string channel = "TELEOP";
  std::string status_channel = "EXPLORE_STATUS";
  std::string operator_id;       // "": user@host
  std::string command_key_file;  // the key the explorer's command_key_file names
  double rate_hz = 10;           // drive messages per second
  int repeat = 5;                // stop, release and a drive's end go out this many times
  double confirm_timeout_s = 2;  // 0: do not wait for EXPLORE_STATUS to show the command
  double max_drive_s = 60;       // longest drive one invocation may ask for
  template <class V>
  void Visit(V& v) {
    v("channel", channel, "TELEOP channel");
    v("status_channel", status_channel,
      "the explorer's status: shows whether the command was obeyed (driven_by)");
    v("operator_id", operator_id, "name carried in every message; empty: user@host");
    v("command_key_file", command_key_file,
      "key (>= 16 random bytes, mode 600) that signs every TELEOP: the explorer's "
      "command_key_file; empty: unsigned (obeyed only by an explorer without a key); "
      "--key-file FILE sets it");
    v("rate_hz", rate_hz,
      "drive messages per second, 2..100 (the explorer ends an override teleop_timeout_s, 0.5 s, "
      "after the last one arrived)");
    v("repeat", repeat,
      "stop, release and the end of a drive are sent this many times, 1/rate_hz apart, "
      "against datagram loss",
      InRange(1, 100));
    v("confirm_timeout_s", confirm_timeout_s,
      "wait this long for EXPLORE_STATUS to show the command obeyed (exit 1 if not); 0: no wait",
      NonNegative());
    v("max_drive_s", max_drive_s, "longest drive one command may ask for", Positive());
  }
  void Validate(common::Validator& check) const;
};

enum class Action { kStop, kRelease, kDrive };

struct Request {
  Action action = Action::kStop;
  double linear_mps = 0;
  double angular_radps = 0;
  double duration_s = 0;  // drive only
};

// "stop" | "release" | "drive LINEAR_MPS ANGULAR_RADPS [SECONDS]" (SECONDS default 1).
// Throws common::ArgError naming what is wrong (unknown word, a number that is not one or not
// finite, a duration outside (0, max_drive_s]).
Request ParseRequest(const std::vector<std::string>& words, const TeleopOptions& options);

// One message to send, `at_s` after the first.
struct Step {
  double at_s = 0;
  bool emergency_stop = false;
  bool override_active = false;
  double linear_mps = 0;
  double angular_radps = 0;
  bool ends_drive = false;  // a zero-speed override that ends a drive (not a release)
};

// stop: `repeat` emergency stops; release: `repeat` messages with neither stop nor override;
// drive: an override every 1/rate_hz for the duration, then `repeat` zero-speed overrides
// ending it (the explorer takes over `teleop_timeout_s` later; a drive never releases an
// emergency stop).
// Every step comes 1/rate_hz after the one before.
std::vector<Step> PlanRequest(const Request& request, const TeleopOptions& options);

// Stamps that always increase: the receiver's CommandGate acts only on a stamp above the last
// one it accepted, so two messages within one microsecond (or a clock stepped back while the
// tool runs) must still go out in order.
class Stamper {
 public:
  int64_t Next(int64_t now_utime) {
    last_ = now_utime > last_ ? now_utime : last_ + 1;
    return last_;
  }

 private:
  int64_t last_ = 0;
};

// Whether the explorer's `driven_by` (EXPLORE_STATUS) shows `action` obeyed.
bool StatusConfirms(Action action, const std::string& driven_by);

// user@host of this process.
std::string DefaultOperatorId();

}  // namespace teleop
}  // namespace sarmap
