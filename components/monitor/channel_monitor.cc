#include "monitor/channel_monitor.h"

#include <cstdio>

namespace sarmap {
namespace monitor {

void ChannelMonitor::OnMessage(const std::string& channel, double now_s, int64_t missed_before) {
  ChannelWindow& w = channels_[channel];
  w.arrivals_s.push_back(now_s);
  ++w.total;
  w.gaps += missed_before;
  Trim(&w, now_s);
}

void ChannelMonitor::Trim(ChannelWindow* w, double now_s) const {
  while (!w->arrivals_s.empty() && w->arrivals_s.front() < now_s - window_s_) w->arrivals_s.pop_front();
}

double ChannelMonitor::RateHz(const std::string& channel, double now_s) {
  auto it = channels_.find(channel);
  if (it == channels_.end()) return 0.0;
  Trim(&it->second, now_s);
  return it->second.arrivals_s.size() / window_s_;
}

std::string ChannelMonitor::Table(double now_s) {
  std::string out;
  char line[160];
  snprintf(line, sizeof(line), "%-22s %9s %10s %8s %8s\n", "channel", "rate_Hz", "total", "gaps", "dropped");
  out += line;
  for (auto& [name, w] : channels_) {
    Trim(&w, now_s);
    snprintf(line, sizeof(line), "%-22s %9.1f %10lld %8lld %8lld\n", name.c_str(),
             w.arrivals_s.size() / window_s_, static_cast<long long>(w.total),
             static_cast<long long>(w.gaps), static_cast<long long>(w.dropped));
    out += line;
  }
  return out;
}

}  // namespace monitor
}  // namespace sarmap
