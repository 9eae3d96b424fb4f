// sarmap-monitor: subscribes to every sarmap channel with its type, checks each message, and
// shows rates, sequence gaps and malformed messages; its own NODE_STATUS carries the counts.
#include <cstdio>
#include <regex>

#include "common/node_main.h"
#include "common/channels.h"
#include "common/node.h"
#include "common/options.h"
#include "monitor/channel_monitor.h"

namespace {

struct MonitorOptions {
  double print_period_s = 2.0;  // 0: never print the table
  double window_s = 2.0;
  std::string channels = ".*";  // regular expression over the default channel names
  std::vector<std::string> extra_channels;  // CHANNEL=type_t pairs beyond the defaults
  template <class V>
  void Visit(V& v) {
    v("print_period_s", print_period_s, "seconds between tables on stdout (0: never)");
    v("window_s", window_s, "window of the rate estimate");
    v("channels", channels, "regular expression selecting default channels to watch");
    v("extra_channels", extra_channels, "more channels to watch, as CHANNEL=type_t");
  }
  void Validate(sarmap::common::Validator& check) const {
    check.NonNegative("print_period_s", print_period_s);
    check.Positive("window_s", window_s);
  }
};

template <class T>
void Watch(sarmap::common::Node* node, sarmap::monitor::ChannelMonitor* monitor,
           const std::string& channel) {
  node->Subscribe<T>(channel, [monitor, channel](const T&, const sarmap::common::ReceiveInfo& info) {
    monitor->OnMessage(channel, info.receive_time_s, info.missed_before);
  }, 100);
}

bool WatchByTypeName(sarmap::common::Node* node, sarmap::monitor::ChannelMonitor* monitor,
                     const std::string& channel, const std::string& type) {
#define SARMAP_WATCH(T)                              \
  if (type == #T) {                                  \
    Watch<sarmap::T>(node, monitor, channel);        \
    return true;                                     \
  }
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_WATCH)
#undef SARMAP_WATCH
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-monitor", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-monitor",
        "Watches every sarmap channel: decodes and checks each message with its type, and\n"
        "prints rates, sequence gaps and malformed-message counts. NODE_STATUS carries the\n"
        "same counts for other tools.");
    sarmap::common::NodeArgs node_args;
    const auto parsed =
        sarmap::common::ParseNodeOptions<MonitorOptions>(&parser, &node_args, argc, argv, "");
    if (!parsed) return 0;
    const MonitorOptions& options = *parsed;
    sarmap::common::Node node("sarmap-monitor", node_args);
    sarmap::monitor::ChannelMonitor monitor(options.window_s);
    const std::regex select(options.channels);
    for (const auto& spec : sarmap::common::DefaultChannels()) {
      if (std::regex_match(spec.channel, select)) {
        WatchByTypeName(&node, &monitor, spec.channel, spec.type);
      }
    }
    for (const auto& pair : options.extra_channels) {
      const auto eq = pair.find('=');
      if (eq == std::string::npos || !WatchByTypeName(&node, &monitor, pair.substr(0, eq), pair.substr(eq + 1))) {
        throw sarmap::common::OptionsError("extra_channels: '" + pair + "' is not CHANNEL=known_type_t");
      }
    }
    if (options.print_period_s > 0) {
      node.AddTimer(options.print_period_s, [&] {
        for (const auto& [channel, stats] : node.stats()) {
          for (int64_t i = monitor.channels().count(channel) ? monitor.channels().at(channel).dropped : 0;
               i < stats.dropped_malformed; ++i) {
            monitor.OnDropped(channel);
          }
        }
        printf("%s\n", monitor.Table(sarmap::common::SteadySeconds()).c_str());
        fflush(stdout);
      });
    }
    return node.Run();
  });
}
