#pragma once
// MonitorNode: subscribes to every sarmap channel with its type (common/channels.h), so each
// message is decoded and checked, and keeps rates, sequence gaps and malformed messages per
// channel (ChannelMonitor); prints them as a table every print_period_s. Its own NODE_STATUS
// carries the counts.

#include <string>
#include <vector>

#include "common/node.h"
#include "common/options.h"
#include "monitor/channel_monitor.h"

namespace sarmap {
namespace monitor {

struct MonitorOptions {
  double print_period_s = 2.0;  // 0: never print the table
  double window_s = 2.0;
  std::string channels = ".*";              // regular expression over the default channel names
  std::vector<std::string> extra_channels;  // CHANNEL=type_t pairs beyond the defaults
  template <class V>
  void Visit(V& v) {
    v("print_period_s", print_period_s, "seconds between tables on stdout (0: never)",
      NonNegative());
    v("window_s", window_s, "window of the rate estimate", Positive());
    v("channels", channels, "regular expression selecting default channels to watch");
    v("extra_channels", extra_channels, "more channels to watch, as CHANNEL=type_t");
  }
};

class MonitorNode {
 public:
  // Throws common::OptionsError for an extra channel that is not CHANNEL=known_type_t.
  MonitorNode(const MonitorOptions& options, common::Node* node);

  // The node runtime's malformed-message counts into the monitor (the table shows both).
  void SyncDropped();
  const ChannelMonitor& monitor() const { return monitor_; }

 private:
  bool Watch(const std::string& channel, const std::string& type);

  common::Node* node_;
  ChannelMonitor monitor_;
};

}  // namespace monitor
}  // namespace sarmap
