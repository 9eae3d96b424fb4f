// sarmap-procman-deputy: runs the commands a verified sheriff orders on this computer.
#include <unistd.h>

#include <cstdlib>
#include <cstring>

#include "common/args.h"
#include "common/lcm_guard.h"
#include "common/logging.h"
#include "common/node.h"
#include "procman/cli_common.h"
#include "procman/deputy.h"
#include "procman/procman_cli.h"

namespace sarmap {
namespace procman {

int RunDeputy(int argc, char** argv) {
  common::ArgParser parser(
      "sarmap-procman-deputy",
      "Runs and watches the commands that a verified sheriff orders for this deputy id.");
  common::NodeArgs node_args;
  std::string id, key_path;
  parser.AddFlag("--id", &id, "deputy name used in the .pmd files (deputy = \"NAME\";)");
  parser.AddFlag("--key", &key_path,
                 "shared HMAC key file (default: key_file of the options; see README: key set-up)");
  parser.AddNodeOptions(&node_args);
  parser.SetEpilog(
      "channels: PM_ORDERS in; PM_INFO (1 Hz and on change), PM_OUTPUT (rate-limited) out.\n"
      "SIGINT/SIGTERM stop every command (signal, then SIGKILL) before the deputy exits;\n"
      "a second one exits at once, killing what is left. Commands die with the deputy\n"
      "(SIGKILL) if it is killed.");
  const std::optional<ProcmanOptions> options =
      ParseCommandLine(&parser, &node_args, argc, argv, "", &key_path);
  if (!options) return 0;  // --help or --print-config
  if (id.empty()) throw common::ArgError("--id NAME is required");
  common::SetLogName("sarmap-procman-deputy[" + id + "]");
  Key key = LoadKeyFileOrArgError(key_path);
  if (!BecomeSubreaper()) {
    SARMAP_LOG(WARN) << "cannot become child subreaper; orphans go to init";
  }
  if (!StartGroupGuardian()) {
    SARMAP_LOG(WARN) << "no group guardian (" << strerror(errno)
                     << "): if this deputy is killed, what its commands forked runs on";
  }

  const std::string url = node_args.lcm_url.empty() ? common::DefaultLcmUrl() : node_args.lcm_url;
  lcm::LCM lcm(url);
  if (!lcm.good()) throw std::runtime_error("cannot initialise LCM on '" + url + "'");
  EventLoop loop(&lcm);
  Deputy deputy(&lcm, *options, id, std::move(key), InheritedEnvironment(OwnDirectory()));
  if (!node_args.bus_key_file.empty()) {
    try {
      deputy.SetBusKey(common::LoadAuthKeyFile(node_args.bus_key_file));
    } catch (const std::runtime_error& e) {
      throw common::ArgError(e.what());
    }
  }
  std::string guard_error;  // hostile LCM fragments (common/lcm_guard.h)
  if (common::GuardLcmReceiveSocket(&lcm, url, &guard_error) < 0) {
    SARMAP_LOG(WARN) << "no filter for hostile LCM fragments: " << guard_error;
  }
  loop.Add(&deputy);
  while (true) {
    if (!loop.RunOnce(1.0)) return 1;
    const int interrupts = EventLoop::Interrupts();
    if (interrupts >= 1) deputy.Shutdown();
    if (deputy.Finished()) break;
    if (interrupts >= 2) {
      SARMAP_LOG(WARN) << "second interrupt: killing what is left";
      break;  // ~Supervisor sends SIGKILL to every tree
    }
  }
  SARMAP_LOG(INFO) << "exiting; refused orders: " << deputy.refused_orders();
  return 0;
}

}  // namespace procman
}  // namespace sarmap
