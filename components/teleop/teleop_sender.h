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

}  // namespace teleop
}  // namespace sarmap
