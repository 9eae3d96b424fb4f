#include "teleop/teleop_sender.h"

#include <unistd.h>

#include <cstdio>
#include <memory>
#include <stdexcept>

#include "common/args.h"
#include "common/logging.h"
#include "common/node_main.h"
#include "common/time.h"
#include "sarmap/explore_status_t.hpp"

namespace sarmap {
namespace teleop {
namespace {

const char* ActionName(Action action) {
  switch (action) {
    case Action::kStop:
      return "emergency stop";
    case Action::kRelease:
      return "release";
    case Action::kDrive:
      return "drive";
  }
  return "?";
}

const char* Expected(Action action) {
  switch (action) {
    case Action::kStop:
      return "driven_by stop";
    case Action::kRelease:
      return "driven_by neither stop nor teleop";
    case Action::kDrive:
      return "driven_by teleop";
  }
  return "?";
}

}  // namespace

common::AuthKey LoadCommandKey(const TeleopOptions& options) {
  common::AuthKey key;
  if (!options.command_key_file.empty()) {
    try {
      key = common::LoadAuthKeyFile(options.command_key_file);
    } catch (const std::runtime_error& e) {
      throw common::ArgError(e.what());
    }
  } else {
    SARMAP_LOG(WARN) << "no command key (--key-file): TELEOP goes out unsigned, and an explorer "
                        "with command_key_file ignores it";
  }
  return key;
}

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

int SendAndConfirm(common::Node* node, const TeleopOptions& options, const Request& request,
                   const common::AuthKey& key) {
  // What EXPLORE_STATUS said, shared with the subscription (which stays on the node).
  struct Heard {
    bool sending = false, confirmed = false;
    std::string last_driven_by;
  };
  const auto heard = std::make_shared<Heard>();
  node->Subscribe<explore_status_t>(
      options.status_channel,
      [heard, action = request.action](const explore_status_t& m, const common::ReceiveInfo&) {
        heard->last_driven_by = common::EscapeForLog(m.driven_by, 64);
        if (heard->sending && StatusConfirms(action, m.driven_by)) heard->confirmed = true;
      });
  TeleopSender sender(node, options, key);

  const std::vector<Step> steps = PlanRequest(request, options);
  const double period_s = 1.0 / options.rate_hz;
  const double start_s = common::SteadySeconds();
  bool interrupted = false;
  size_t sent = 0;
  heard->sending = true;
  for (size_t i = 0; i < steps.size(); ++i) {
    if (!interrupted) {
      for (double wait_s; (wait_s = start_s + steps[i].at_s - common::SteadySeconds()) > 0;) {
        if (!node->SpinOnce(wait_s)) {
          interrupted = true;
          break;
        }
      }
    }
    if (interrupted) {
      // Ctrl-C: a drive ends at once (its end messages still go out); a stop or a release is
      // sent in full.
      if (steps[i].override_active && !steps[i].ends_drive) continue;
      usleep(static_cast<useconds_t>(period_s * 1e6));
    }
    sender.Send(steps[i]);
    ++sent;
  }
  printf("sarmap-teleop: %s sent (%zu messages on %s, %s)\n", ActionName(request.action), sent,
         options.channel.c_str(), sender.signs() ? "signed" : "unsigned");
  if (interrupted) return 1;
  if (options.confirm_timeout_s <= 0) return 0;

  const double until_s = common::SteadySeconds() + options.confirm_timeout_s;
  while (!heard->confirmed && common::SteadySeconds() < until_s) {
    if (!node->SpinOnce(until_s - common::SteadySeconds())) return 1;
  }
  if (heard->confirmed) {
    printf("sarmap-teleop: %s shows %s: obeyed\n", options.status_channel.c_str(),
           Expected(request.action));
    return 0;
  }
  fprintf(
      stderr,
      "sarmap-teleop: no %s with %s within %.1f s (last heard: %s): not obeyed - is "
      "sarmap-explore running, and is this its command key?\n",
      options.status_channel.c_str(), Expected(request.action), options.confirm_timeout_s,
      heard->last_driven_by.empty() ? "nothing" : ("driven_by " + heard->last_driven_by).c_str());
  return 1;
}

int RunTeleop(int argc, char** argv) {
  common::ArgParser parser(
      "sarmap-teleop",
      "The operator's TELEOP: an emergency stop (held by sarmap-explore until released), its\n"
      "release, or a drive at LINEAR_MPS and ANGULAR_RADPS for SECONDS (default 1; Ctrl-C\n"
      "ends it early). With a command key every message is signed: an explorer with\n"
      "command_key_file obeys only signed TELEOP. Waits for EXPLORE_STATUS to show the command\n"
      "obeyed: exit 0 when it does, 1 when it does not within confirm_timeout_s.");
  common::NodeArgs args;
  std::string key_file;
  std::vector<std::string> words;
  parser.AddFlag("--key-file", &key_file,
                 "command key (the explorer's command_key_file); overrides command_key_file");
  parser.AddRest("COMMAND", &words,
                 "stop | release | drive LINEAR_MPS ANGULAR_RADPS [SECONDS] (options first)");
  parser.SetEpilog(
      "Examples:\n"
      "  sarmap-teleop --key-file ~/.config/sarmap/procman.key stop\n"
      "  sarmap-teleop --key-file ~/.config/sarmap/procman.key drive -0.2 0 1.5\n"
      "  sarmap-teleop --key-file ~/.config/sarmap/procman.key release\n");
  auto parsed =
      common::ParseNodeOptions<TeleopOptions>(&parser, &args, argc, argv, "config/teleop.yaml");
  if (!parsed) return 0;
  common::SetLogName("sarmap-teleop");
  TeleopOptions options = *parsed;
  if (!key_file.empty()) options.command_key_file = key_file;
  const Request request = ParseRequest(words, options);

  const common::AuthKey key = LoadCommandKey(options);
  common::Node node("sarmap-teleop", args);
  return SendAndConfirm(&node, options, request, key);
}

}  // namespace teleop
}  // namespace sarmap
