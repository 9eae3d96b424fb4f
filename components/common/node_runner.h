#pragma once
// The whole main() of a node whose logic is an adapter class:
//
//   int main(int argc, char** argv) {
//     return sarmap::common::RunNode<XNode, XNodeOptions>(
//         {"sarmap-x", "What it does.", "Channels ...", "config/x.yaml"}, argc, argv);
//   }
//
// The adapter is constructed as XNode(const XNodeOptions&, common::Node*): it subscribes,
// advertises and adds its timers there. After the node stops (SIGINT, SIGTERM) the runner calls
// its Finish() (flush queues, publish last, save state) when it has one.
// Errors a user can cause (bad arguments, options or files) end in one line and exit code 2
// (RunMain).
//
// A node may also take shorthand flags for common overrides: {"--file", "play this file",
// {"source=file", "file={}"}} adds `--file F`, which stands for `--set source=file --set file=F`
// (placed before the command line's own --set, which therefore win).

#include <cstdio>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/args.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/options.h"
#include "common/robot_config.h"

namespace sarmap {
namespace common {

struct ShorthandFlag {
  std::string flag;               // e.g. "--file"
  std::string help;               // its line in --help
  std::vector<std::string> sets;  // the overrides it stands for; "{}" is the flag's value
};

struct NodeInfo {
  const char* name;            // program and node name, e.g. "sarmap-people-map"
  const char* description;     // --help summary
  const char* epilog;          // --help text after the options ("" for none)
  const char* default_config;  // e.g. "config/people_map.yaml"
  std::vector<ShorthandFlag> shorthands = {};
};

namespace internal {
template <class T, class = void>
struct HasFinish : std::false_type {};
template <class T>
struct HasFinish<T, std::void_t<decltype(std::declval<T&>().Finish())>> : std::true_type {};
}  // namespace internal

template <class Adapter, class Options>
int RunNode(const NodeInfo& info, int argc, char** argv) {
  return RunMain(info.name, [&]() -> int {
    ArgParser parser(info.name, info.description);
    if (info.epilog != nullptr && *info.epilog != '\0') parser.SetEpilog(info.epilog);
    NodeArgs args;
    parser.AddNodeOptions(&args, info.default_config);
    std::vector<std::string> values(info.shorthands.size());
    for (size_t i = 0; i < info.shorthands.size(); ++i)
      parser.AddFlag(info.shorthands[i].flag, &values[i], info.shorthands[i].help);
    if (!parser.Parse(argc, argv)) return 0;  // --help
    std::vector<std::string> overrides;
    for (size_t i = 0; i < info.shorthands.size(); ++i) {
      if (values[i].empty()) continue;
      for (std::string set : info.shorthands[i].sets) {
        const size_t at = set.find("{}");
        if (at != std::string::npos) set.replace(at, 2, values[i]);
        overrides.push_back(set);
      }
    }
    overrides.insert(overrides.end(), args.overrides.begin(), args.overrides.end());
    const Options options = LoadOptions<Options>(ResolveConfigPath(args.config_path), overrides);
    if (args.print_config) {
      fputs(OptionsToYaml(options, true).c_str(), stdout);
      return 0;
    }
    SetLogLevel(ParseLogLevel(args.log_level));
    Node node(info.name, args);
    Adapter adapter(options, &node);
    const int code = node.Run();
    if constexpr (internal::HasFinish<Adapter>::value) adapter.Finish();
    return code;
  });
}

}  // namespace common
}  // namespace sarmap
