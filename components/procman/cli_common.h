#pragma once
// What the command lines of sarmap-procman and sarmap-procman-deputy (procman_cli.h) share:
// the options and the key file.

#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "common/args.h"
#include "common/logging.h"
#include "common/options.h"
#include "procman/order_auth.h"
#include "procman/procman_options.h"

namespace sarmap {
namespace procman {

// Parses the command line, applies --log-level (and names the log `log_name` unless it is
// empty), loads the options (--config, --set) and takes `*key_path` from them unless --key set
// it. Nothing, for an exit with status 0, after --help or --print-config (printed to stdout).
inline std::optional<ProcmanOptions> ParseCommandLine(common::ArgParser* parser,
                                                      common::NodeArgs* node_args, int argc,
                                                      char** argv, const std::string& log_name,
                                                      std::string* key_path) {
  if (!parser->Parse(argc, argv)) return std::nullopt;
  common::SetLogLevel(common::ParseLogLevel(node_args->log_level));
  if (!log_name.empty()) common::SetLogName(log_name);
  ProcmanOptions options =
      common::LoadOptions<ProcmanOptions>(node_args->config_path, node_args->overrides);
  if (key_path->empty()) *key_path = options.key_file;
  if (node_args->print_config) {
    std::cout << common::OptionsToYaml(options, true);
    return std::nullopt;
  }
  return options;
}

// The shared HMAC key of `path`; a missing or unusable key file is a command-line error.
inline Key LoadKeyFileOrArgError(const std::string& path) {
  try {
    return LoadKeyFile(path);
  } catch (const std::runtime_error& e) {
    throw common::ArgError(e.what());
  }
}

}  // namespace procman
}  // namespace sarmap
