// sarmap-teleop: the operator's TELEOP from a terminal. An emergency stop, its release, or a
// drive for some seconds, signed with the command key so that an explorer with
// command_key_file obeys it; then EXPLORE_STATUS says whether it was obeyed.
#include <unistd.h>

#include <cstdio>
#include <stdexcept>

#include "common/command_auth.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/time.h"
#include "sarmap/explore_status_t.hpp"
#include "teleop/teleop.h"
#include "teleop/teleop_sender.h"

namespace {

using namespace sarmap;

const char* ActionName(teleop::Action action) {
  switch (action) {
    case teleop::Action::kStop:
      return "emergency stop";
    case teleop::Action::kRelease:
      return "release";
    case teleop::Action::kDrive:
      return "drive";
  }
  return "?";
}

const char* Expected(teleop::Action action) {
  switch (action) {
    case teleop::Action::kStop:
      return "driven_by stop";
    case teleop::Action::kRelease:
      return "driven_by neither stop nor teleop";
    case teleop::Action::kDrive:
      return "driven_by teleop";
  }
  return "?";
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-teleop", [&] {
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
    auto parsed = common::ParseNodeOptions<teleop::TeleopOptions>(&parser, &args, argc, argv,
                                                                  "config/teleop.yaml");
    if (!parsed) return 0;
    common::SetLogName("sarmap-teleop");
    teleop::TeleopOptions options = *parsed;
    if (!key_file.empty()) options.command_key_file = key_file;
    const teleop::Request request = teleop::ParseRequest(words, options);

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

    common::Node node("sarmap-teleop", args);
    bool sending = false, confirmed = false;
    std::string last_driven_by;
    node.Subscribe<explore_status_t>(
        options.status_channel, [&](const explore_status_t& m, const common::ReceiveInfo&) {
          last_driven_by = common::EscapeForLog(m.driven_by, 64);
          if (sending && teleop::StatusConfirms(request.action, m.driven_by)) confirmed = true;
        });
    teleop::TeleopSender sender(&node, options, key);

    const std::vector<teleop::Step> steps = teleop::PlanRequest(request, options);
    const double period_s = 1.0 / options.rate_hz;
    const double start_s = common::SteadySeconds();
    bool interrupted = false;
    size_t sent = 0;
    sending = true;
    for (size_t i = 0; i < steps.size(); ++i) {
      if (!interrupted) {
        for (double wait_s; (wait_s = start_s + steps[i].at_s - common::SteadySeconds()) > 0;) {
          if (!node.SpinOnce(wait_s)) {
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
    while (!confirmed && common::SteadySeconds() < until_s) {
      if (!node.SpinOnce(until_s - common::SteadySeconds())) return 1;
    }
    if (confirmed) {
      printf("sarmap-teleop: %s shows %s: obeyed\n", options.status_channel.c_str(),
             Expected(request.action));
      return 0;
    }
    fprintf(stderr,
            "sarmap-teleop: no %s with %s within %.1f s (last heard: %s): not obeyed - is "
            "sarmap-explore running, and is this its command key?\n",
            options.status_channel.c_str(), Expected(request.action), options.confirm_timeout_s,
            last_driven_by.empty() ? "nothing" : ("driven_by " + last_driven_by).c_str());
    return 1;
  });
}
