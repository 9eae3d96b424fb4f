#pragma once
// Publishes the operator's TELEOP: stamped on the wall clock (always increasing), sequence
// numbered, and signed with the command key when one is given (common/command_auth.h), so an
// explorer with command_key_file obeys it.

#include <string>

#include "common/command_auth.h"
#include "common/node.h"
#include "sarmap/teleop_t.hpp"
#include "teleop/teleop.h"

namespace sarmap {
namespace teleop {

// The command key named by options.command_key_file (empty when none is named: TELEOP goes out
// unsigned, with a warning). Throws common::ArgError when the file cannot be used.
common::AuthKey LoadCommandKey(const TeleopOptions& options);

// The message for `step`, stamped `utime`, unsigned.
teleop_t MakeTeleop(const Step& step, const std::string& operator_id, int64_t utime);

class TeleopSender {
 public:
  // An empty key sends unsigned messages.
  TeleopSender(common::Node* node, const TeleopOptions& options, common::AuthKey key);
  bool signs() const { return !key_.empty(); }

  // Publishes `step`; returns the message as sent. Throws std::runtime_error when it cannot be
  // signed (an operator id holding a NUL byte).
  teleop_t Send(const Step& step);

 private:
  common::Node::Publisher<teleop_t> pub_;
  common::AuthKey key_;
  std::string operator_id_;
  Stamper stamper_;
};

// sarmap-teleop's run: sends `request` as its planned steps on the node's bus at
// options.rate_hz (Ctrl-C ends a drive at once, its end messages still sent; a stop or a
// release goes out in full), then waits up to confirm_timeout_s for EXPLORE_STATUS to show it
// obeyed. Prints what it sent and the outcome; returns the exit status: 0 obeyed (or no
// confirmation asked for), 1 not obeyed or interrupted.
int SendAndConfirm(common::Node* node, const TeleopOptions& options, const Request& request,
                   const common::AuthKey& key);

// sarmap-teleop's command line (--help explains it): options, the command key, the node, then
// SendAndConfirm. Returns the exit status; throws common::ArgError on a bad command line.
int RunTeleop(int argc, char** argv);

}  // namespace teleop
}  // namespace sarmap
