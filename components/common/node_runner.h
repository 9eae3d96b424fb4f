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

#include <type_traits>
#include <utility>

#include "common/args.h"
#include "common/node.h"
#include "common/node_main.h"

namespace sarmap {
namespace common {

struct NodeInfo {
  const char* name;            // program and node name, e.g. "sarmap-people-map"
  const char* description;     // --help summary
  const char* epilog;          // --help text after the options ("" for none)
  const char* default_config;  // e.g. "config/people_map.yaml"
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
    const auto options = ParseNodeOptions<Options>(&parser, &args, argc, argv, info.default_config);
    if (!options) return 0;  // --help or --print-config
    Node node(info.name, args);
    Adapter adapter(*options, &node);
    const int code = node.Run();
    if constexpr (internal::HasFinish<Adapter>::value) adapter.Finish();
    return code;
  });
}

}  // namespace common
}  // namespace sarmap
