#include "teleop/teleop.h"

#include <pwd.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include "common/args.h"

namespace sarmap {
namespace teleop {

void TeleopOptions::Validate(common::Validator& check) const {
  check.That(!channel.empty(), "channel", "must not be empty");
  // Below 2 Hz the explorer's 0.5 s dead man would end an override between two messages.
  check.InRange("rate_hz", rate_hz, 2, 100);
  check.That(operator_id.find('\0') == std::string::npos, "operator_id",
             "must not hold a NUL byte (it could not be signed)");
}

namespace {

double ParseNumber(const std::string& word, const std::string& what) {
  char* end = nullptr;
  const double value = std::strtod(word.c_str(), &end);
  if (word.empty() || end != word.c_str() + word.size() || !std::isfinite(value)) {
    throw common::ArgError(what + ": '" + word + "' is not a finite number");
  }
  return value;
}

}  // namespace

Request ParseRequest(const std::vector<std::string>& words, const TeleopOptions& options) {
  const std::string usage = "expected stop, release or drive LINEAR_MPS ANGULAR_RADPS [SECONDS]";
  if (words.empty()) throw common::ArgError("no command: " + usage);
  Request request;
  const std::string& verb = words[0];
  if (verb == "stop" || verb == "release") {
    if (words.size() != 1) throw common::ArgError(verb + " takes no arguments");
    request.action = verb == "stop" ? Action::kStop : Action::kRelease;
    return request;
  }
  if (verb != "drive") throw common::ArgError("unknown command '" + verb + "': " + usage);
  if (words.size() < 3 || words.size() > 4) {
    throw common::ArgError("drive takes LINEAR_MPS ANGULAR_RADPS [SECONDS]");
  }
  request.action = Action::kDrive;
  request.linear_mps = ParseNumber(words[1], "LINEAR_MPS");
  request.angular_radps = ParseNumber(words[2], "ANGULAR_RADPS");
  request.duration_s = words.size() == 4 ? ParseNumber(words[3], "SECONDS") : 1.0;
  if (!(request.duration_s > 0) || request.duration_s > options.max_drive_s) {
    throw common::ArgError("SECONDS must be in (0, " + std::to_string(options.max_drive_s) +
                           "] (max_drive_s), is " + words[3]);
  }
  return request;
}

std::vector<Step> PlanRequest(const Request& request, const TeleopOptions& options) {
  const double period_s = 1.0 / options.rate_hz;
  std::vector<Step> steps;
  auto add = [&](Step step) {
    step.at_s = static_cast<double>(steps.size()) * period_s;
    steps.push_back(step);
  };
  Step end;  // neither stop nor override: the explorer drives again
  switch (request.action) {
    case Action::kStop: {
      Step stop;
      stop.emergency_stop = true;
      for (int i = 0; i < options.repeat; ++i) add(stop);
      break;
    }
    case Action::kRelease:
      for (int i = 0; i < options.repeat; ++i) add(end);
      break;
    case Action::kDrive: {
      Step drive;
      drive.override_active = true;
      drive.linear_mps = request.linear_mps;
      drive.angular_radps = request.angular_radps;
      const int n =
          std::max(1, static_cast<int>(std::ceil(request.duration_s * options.rate_hz - 1e-9)));
      for (int i = 0; i < n; ++i) add(drive);
      Step halt;
      halt.override_active = true;
      halt.ends_drive = true;
      for (int i = 0; i < options.repeat; ++i) add(halt);
      break;
    }
  }
  return steps;
}

bool StatusConfirms(Action action, const std::string& driven_by) {
  switch (action) {
    case Action::kStop:
      return driven_by == "stop";
    case Action::kDrive:
      return driven_by == "teleop";
    case Action::kRelease:
      return !driven_by.empty() && driven_by != "stop" && driven_by != "teleop";
  }
  return false;
}

std::string DefaultOperatorId() {
  std::string user = "unknown";
  if (const passwd* pw = getpwuid(getuid())) user = pw->pw_name;
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) != 0) host[0] = 0;
  return user + "@" + (host[0] ? host : "localhost");
}

}  // namespace teleop
}  // namespace sarmap
