#include "monitor/monitor_node.h"

#include <cstdio>
#include <regex>

#include "common/channels.h"

namespace sarmap {
namespace monitor {
namespace {

template <class T>
void WatchTyped(common::Node* node, ChannelMonitor* monitor, const std::string& channel) {
  node->Subscribe<T>(
      channel,
      [monitor, channel](const T&, const common::ReceiveInfo& info) {
        monitor->OnMessage(channel, info.receive_time_s, info.missed_before);
      },
      100);
}

}  // namespace

MonitorNode::MonitorNode(const MonitorOptions& options, common::Node* node)
    : node_(node), monitor_(options.window_s) {
  const std::regex select(options.channels);
  for (const auto& spec : common::DefaultChannels()) {
    if (std::regex_match(spec.channel, select)) Watch(spec.channel, spec.type);
  }
  for (const auto& pair : options.extra_channels) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos || !Watch(pair.substr(0, eq), pair.substr(eq + 1))) {
      throw common::OptionsError("extra_channels: '" + pair + "' is not CHANNEL=known_type_t");
    }
  }
  if (options.print_period_s > 0) {
    node->AddTimer(options.print_period_s, [this] {
      SyncDropped();
      printf("%s\n", monitor_.Table(common::SteadySeconds()).c_str());
      fflush(stdout);
    });
  }
}

bool MonitorNode::Watch(const std::string& channel, const std::string& type) {
#define SARMAP_WATCH(T)                               \
  if (type == #T) {                                   \
    WatchTyped<sarmap::T>(node_, &monitor_, channel); \
    return true;                                      \
  }
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_WATCH)
#undef SARMAP_WATCH
  return false;
}

void MonitorNode::SyncDropped() {
  for (const auto& [channel, stats] : node_->stats()) {
    const auto known = monitor_.channels().find(channel);
    for (int64_t i = known != monitor_.channels().end() ? known->second.dropped : 0;
         i < stats.dropped_malformed; ++i) {
      monitor_.OnDropped(channel);
    }
  }
}

}  // namespace monitor
}  // namespace sarmap
