#pragma once
// Rates, gaps and drops of a set of channels over a sliding window: the core of
// sarmap-monitor, free of LCM so it can be fed from a log or tested directly.

#include <cstdint>
#include <deque>
#include <map>
#include <string>

namespace sarmap {
namespace monitor {

struct ChannelWindow {
  std::deque<double> arrivals_s;  // receive times inside the window
  int64_t total = 0;
  int64_t gaps = 0;
  int64_t dropped = 0;
  double last_latency_s = 0;      // receive time minus header time, when clocks are shared
};

class ChannelMonitor {
 public:
  explicit ChannelMonitor(double window_s = 2.0) : window_s_(window_s) {}
  void OnMessage(const std::string& channel, double now_s, int64_t missed_before);
  void OnDropped(const std::string& channel) { ++channels_[channel].dropped; }
  // Messages per second over the window ending at now_s.
  double RateHz(const std::string& channel, double now_s);
  // A fixed-width table of every channel seen.
  std::string Table(double now_s);
  const std::map<std::string, ChannelWindow>& channels() const { return channels_; }

 private:
  void Trim(ChannelWindow* w, double now_s) const;
  double window_s_;
  std::map<std::string, ChannelWindow> channels_;
};

}  // namespace monitor
}  // namespace sarmap
