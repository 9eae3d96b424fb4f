#pragma once
// The start of every node's main(): parse the command line, load and validate the options
// (config file found by ResolveConfigPath, --set overrides), honour --print-config and
// --log-level.
//
//   common::ArgParser parser("sarmap-x", "What it does.");
//   common::NodeArgs args;
//   auto options = common::ParseNodeOptions<XOptions>(&parser, &args, argc, argv, "config/x.yaml");
//   if (!options) return 0;  // --help or --print-config

#include <cstdio>
#include <optional>
#include <string>

#include "common/args.h"
#include "common/logging.h"
#include "common/options.h"
#include "common/robot_config.h"

namespace sarmap {
namespace common {

template <class Options>
std::optional<Options> ParseNodeOptions(ArgParser* parser, NodeArgs* args, int argc, char** argv,
                                        const std::string& default_config) {
  parser->AddNodeOptions(args, default_config);
  if (!parser->Parse(argc, argv)) return std::nullopt;
  Options options = LoadOptions<Options>(ResolveConfigPath(args->config_path), args->overrides);
  if (args->print_config) {
    fputs(OptionsToYaml(options, true).c_str(), stdout);
    return std::nullopt;
  }
  SetLogLevel(ParseLogLevel(args->log_level));
  return options;
}

}  // namespace common
}  // namespace sarmap
