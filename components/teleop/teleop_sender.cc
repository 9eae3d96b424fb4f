#include "teleop/teleop_sender.h"

#include <stdexcept>

#include "common/time.h"

namespace sarmap {
namespace teleop {

teleop_t MakeTeleop(const Step& step, const std::string& operator_id, int64_t utime) {
  teleop_t m{};
  m.header.utime = utime;
  m.header.frame = "base";
  m.operator_id = operator_id;
  m.override_active = step.override_active;
  m.emergency_stop = step.emergency_stop;
  m.linear_mps = step.linear_mps;
  m.angular_radps = step.angular_radps;
  return m;
}

TeleopSender::TeleopSender(common::Node* node, const TeleopOptions& options, common::AuthKey key)
    : pub_(node->Advertise<teleop_t>(options.channel)),
      key_(std::move(key)),
      operator_id_(options.operator_id.empty() ? DefaultOperatorId() : options.operator_id) {}

teleop_t TeleopSender::Send(const Step& step) {
  teleop_t m = MakeTeleop(step, operator_id_, stamper_.Next(common::WallClockUtime()));
  // Signed after the sequence number is set; a message that cannot be signed is not sent.
  pub_.Publish(&m, [&](teleop_t* msg) {
    if (!key_.empty() && !common::SignMessage(key_, msg)) {
      throw std::runtime_error("TELEOP cannot be signed (a NUL byte in operator_id)");
    }
  });
  return m;
}

}  // namespace teleop
}  // namespace sarmap
