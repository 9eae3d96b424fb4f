#include "log-tools/stack_perf.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace sarmap {
namespace logtools {
namespace {

double Mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / values.size();
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  // Nearest rank: the smallest value with at least q of the samples at or below it.
  const size_t rank = static_cast<size_t>(std::ceil(q * values.size()));
  return values[std::min(values.size() - 1, rank == 0 ? 0 : rank - 1)];
}

LatencyStats Latencies(const std::map<int64_t, int64_t>& from, const std::map<int64_t, int64_t>& to) {
  std::vector<double> ms;
  for (const auto& [utime, receive_us] : to) {
    const auto it = from.find(utime);
    if (it == from.end()) continue;
    ms.push_back((receive_us - it->second) * 1e-3);
  }
  LatencyStats stats;
  stats.count = static_cast<int>(ms.size());
  if (ms.empty()) return stats;
  stats.median_ms = Quantile(ms, 0.5);
  stats.p95_ms = Quantile(ms, 0.95);
  stats.p99_ms = Quantile(ms, 0.99);
  stats.max_ms = *std::max_element(ms.begin(), ms.end());
  return stats;
}

}  // namespace

StackPerf::StackPerf(std::vector<std::string> exclude, double keep_radius_m)
    : exclude_(std::move(exclude)), keep_radius_m_(keep_radius_m) {}

void StackPerf::SetPeriod(double period_s, double compare_from_s) {
  period_s_ = std::isfinite(period_s) ? std::max(0.0, period_s) : 0.0;
  compare_from_s_ = std::isfinite(compare_from_s) ? std::max(0.0, compare_from_s) : 0.0;
}

bool StackPerf::Excluded(const std::string& command) const {
  return std::any_of(exclude_.begin(), exclude_.end(), [&](const std::string& e) {
    return !e.empty() && command.find(e) != std::string::npos;
  });
}

void StackPerf::AddCommandSample(const std::string& deputy, const std::string& command,
                                 bool running, double cpu_percent, int64_t rss_bytes,
                                 int restart_count, int64_t receive_us) {
  Samples& s = commands_[deputy + "/" + command];
  if (s.first_restarts < 0) s.first_restarts = restart_count;
  s.last_restarts = restart_count;
  if (!running || !std::isfinite(cpu_percent)) return;
  s.cpu.push_back(cpu_percent);
  s.max_rss_bytes = std::max(s.max_rss_bytes, static_cast<double>(rss_bytes));
  if (period_s_ > 0) {
    if (first_sample_us_ < 0 || receive_us < first_sample_us_) first_sample_us_ = receive_us;
    s.timed.push_back({receive_us, cpu_percent, static_cast<double>(rss_bytes)});
  }
}

void StackPerf::SummariseWindows(StackPerfSummary* out) const {
  if (period_s_ <= 0 || first_sample_us_ < 0) return;
  const auto seconds_from_start = [&](int64_t us) { return (us - first_sample_us_) * 1e-6; };
  int num_windows = 1;  // set below, once the span is known
  const auto window_of = [&](int64_t us) {
    return std::clamp(static_cast<int>(std::floor(seconds_from_start(us) / period_s_)), 0,
                      num_windows - 1);
  };
  int64_t last_us = first_sample_us_;
  for (const auto& [name, s] : commands_)
    for (const Sample& x : s.timed) last_us = std::max(last_us, x.receive_us);
  const double span_s = seconds_from_start(last_us);
  num_windows = 1 + static_cast<int>(std::floor(span_s / period_s_));
  // The stack's CPU per second of reports: each process's last sample in that second (a deputy
  // reports every second; several deputies' reports of one second add up).
  std::vector<std::map<int64_t, std::map<std::string, double>>> per_second(num_windows);
  out->windows.resize(num_windows);
  for (int w = 0; w < num_windows; ++w) {
    out->windows[w].start_s = w * period_s_;
    out->windows[w].end_s = std::min(span_s, (w + 1) * period_s_);
  }
  for (const auto& [name, s] : commands_) {
    const bool excluded = Excluded(name);
    std::vector<std::vector<double>> cpu(num_windows);
    std::vector<double> rss_end(num_windows, -1.0);
    double rss_then = -1.0, rss_end_all = -1.0;
    for (const Sample& x : s.timed) {
      const double t = seconds_from_start(x.receive_us);
      const int w = window_of(x.receive_us);
      cpu[w].push_back(x.cpu_percent);
      rss_end[w] = x.rss_bytes;  // samples arrive in time order
      if (t <= compare_from_s_) rss_then = x.rss_bytes;
      rss_end_all = x.rss_bytes;
      if (!excluded) per_second[w][static_cast<int64_t>(std::floor(t))][name] = x.cpu_percent;
    }
    for (int w = 0; w < num_windows; ++w) {
      if (cpu[w].empty()) continue;
      WindowUsage u;
      u.command = name;
      u.samples = static_cast<int>(cpu[w].size());
      u.mean_cpu_percent = Mean(cpu[w]);
      u.p95_cpu_percent = Quantile(cpu[w], 0.95);
      u.rss_end_mb = rss_end[w] / 1e6;
      u.excluded = excluded;
      out->windows[w].processes.push_back(u);
    }
    if (span_s > compare_from_s_ && rss_then >= 0)
      out->rss_growth.push_back({name, rss_then / 1e6, rss_end_all / 1e6});
  }
  // Inputs: each process's counter increments, credited to the window of the report.
  for (const auto& [key, reports] : inputs_) {
    InputCounters before;
    for (const InputCounters& c : reports) {
      const int w = window_of(c.receive_us);
      // (A late message can fill a gap counted before: the counter may go down.)
      out->windows[w].inputs_received += c.received - before.received;
      out->windows[w].input_sequence_gaps += c.sequence_gaps - before.sequence_gaps;
      before = c;
    }
  }
  for (const auto& [node, texts] : status_texts_) {
    std::vector<const std::string*> last(num_windows, nullptr);
    for (const StatusText& t : texts) {
      last[window_of(t.receive_us)] = &t.text;
    }
    for (int w = 0; w < num_windows; ++w)
      if (last[w]) out->windows[w].node_status.emplace_back(node, *last[w]);
  }
  for (int w = 0; w < num_windows; ++w) {
    std::vector<double> totals;
    for (const auto& [second, by_command] : per_second[w]) {
      double total = 0.0;
      for (const auto& [name, c] : by_command) total += c;
      totals.push_back(total);
    }
    if (totals.empty()) continue;
    out->windows[w].stack_cpu_mean_percent = Mean(totals);
    out->windows[w].stack_cpu_p95_percent = Quantile(totals, 0.95);
  }
  out->compare_from_s = compare_from_s_;
}

void StackPerf::AddMachineLoad(double cpu_load_fraction) {
  if (std::isfinite(cpu_load_fraction)) machine_load_.push_back(cpu_load_fraction);
}

void StackPerf::AddNodeStatusText(const std::string& node, const std::string& text,
                                  int64_t receive_us) {
  if (period_s_ <= 0 || text.empty()) return;
  status_texts_[node].push_back({receive_us, text});
}

void StackPerf::AddNodeInput(const std::string& node, int32_t pid, const std::string& channel,
                             int64_t received, int64_t dropped_malformed, int64_t handler_errors,
                             int64_t sequence_gaps, int64_t receive_us) {
  auto& reports = inputs_[{node, channel, pid}];
  const InputCounters c{receive_us, received, dropped_malformed, handler_errors, sequence_gaps};
  if (period_s_ > 0 || reports.empty())
    reports.push_back(c);
  else
    reports.back() = c;
}

void StackPerf::AddDepthFrame(int64_t capture_utime, int64_t receive_us) {
  depth_receive_us_.emplace(capture_utime, receive_us);
}
void StackPerf::AddPeopleVisual(int64_t capture_utime, int64_t receive_us, int people_seen) {
  visual_receive_us_.emplace(capture_utime, receive_us);
  if (people_seen > 0) seen_capture_utimes_.insert(capture_utime);
}
void StackPerf::AddPeopleMap(int64_t capture_utime, int64_t receive_us) {
  map_receive_us_.emplace(capture_utime, receive_us);
}

void StackPerf::AddPeopleMapSnapshot(int64_t seq, const std::vector<std::array<double, 2>>& people_xy_m) {
  if (last_map_seq_ >= 0) {
    const bool continues = seq > last_map_seq_ && seq - last_map_seq_ <= kMaxSeqStep;
    const bool starts_again = seq < last_map_seq_ && seq >= 0 && seq < kMaxSeqStep;
    if (!continues && !starts_again) return;
  }
  if (last_map_seq_ >= 0 && seq < last_map_seq_) {
    // A new process: compare with what the previous one reported last.
    ++map_restarts_;
    awaiting_first_after_restart_ = true;
  }
  if (awaiting_first_after_restart_) {
    awaiting_first_after_restart_ = false;
    people_before_restarts_ += static_cast<int>(last_map_people_.size());
    for (const auto& before : last_map_people_) {
      const bool kept = std::any_of(people_xy_m.begin(), people_xy_m.end(), [&](const std::array<double, 2>& p) {
        return std::hypot(p[0] - before[0], p[1] - before[1]) <= keep_radius_m_;
      });
      people_kept_ += kept ? 1 : 0;
    }
  }
  last_map_seq_ = seq;
  last_map_people_ = people_xy_m;
}

StackPerfSummary StackPerf::Summarise() const {
  StackPerfSummary out;
  for (const auto& [name, s] : commands_) {
    ProcessUsage u;
    u.command = name;
    u.samples = static_cast<int>(s.cpu.size());
    u.mean_cpu_percent = Mean(s.cpu);
    u.p95_cpu_percent = Quantile(s.cpu, 0.95);
    u.max_rss_mb = s.max_rss_bytes / 1e6;
    u.restarts = std::max(0, s.last_restarts - std::max(0, s.first_restarts));
    u.excluded = Excluded(name);
    (u.excluded ? out.excluded_cpu_percent : out.stack_cpu_percent) += u.mean_cpu_percent;
    out.processes.push_back(u);
  }
  out.machine_load_percent = 100.0 * Mean(machine_load_);
  out.depth_frames = static_cast<int>(depth_receive_us_.size());
  out.depth_to_people_visual = Latencies(depth_receive_us_, visual_receive_us_);
  std::map<int64_t, int64_t> seen_depth;
  for (int64_t t : seen_capture_utimes_) {
    const auto it = depth_receive_us_.find(t);
    if (it != depth_receive_us_.end()) seen_depth.emplace(t, it->second);
  }
  out.depth_to_people_map = Latencies(seen_depth, map_receive_us_);
  out.people_map_restarts = map_restarts_;
  out.people_before_restarts = people_before_restarts_;
  out.people_kept_across_restarts = people_kept_;
  std::map<std::pair<std::string, std::string>, InputUsage> inputs;
  for (const auto& [key, reports] : inputs_) {
    const auto& [node, channel, pid] = key;
    InputUsage& u = inputs[{node, channel}];
    u.node = node;
    u.channel = channel;
    const InputCounters& last = reports.back();
    u.received += last.received;
    u.dropped_malformed += last.dropped_malformed;
    u.handler_errors += last.handler_errors;
    u.sequence_gaps += last.sequence_gaps;
  }
  for (auto& [key, u] : inputs) out.inputs.push_back(u);
  SummariseWindows(&out);
  return out;
}

std::string StackPerfText(const StackPerfSummary& summary) {
  std::ostringstream out;
  char line[256];
  if (summary.processes.empty()) {
    out << "no launcher reports (PM_INFO) in the log: CPU per process unknown (run the stack under\n"
           "sarmap-procman to have them recorded)\n";
  } else {
    snprintf(line, sizeof(line), "%-40s %8s %9s %9s %9s %8s\n", "process (deputy/command)", "samples",
             "cpu_mean%", "cpu_p95%", "rss_MB", "restarts");
    out << line;
    for (const auto& p : summary.processes) {
      snprintf(line, sizeof(line), "%-40s %8d %9.1f %9.1f %9.1f %8d%s\n", p.command.c_str(), p.samples,
               p.mean_cpu_percent, p.p95_cpu_percent, p.max_rss_mb, p.restarts,
               p.excluded ? "  (not counted)" : "");
      out << line;
    }
    snprintf(line, sizeof(line),
             "stack CPU: %.1f %% of one core (%.2f cores); not counted: %.1f %%; machine load %.1f %% of all cores\n",
             summary.stack_cpu_percent, summary.stack_cpu_percent / 100.0, summary.excluded_cpu_percent,
             summary.machine_load_percent);
    out << line;
  }
  const auto latency = [&](const char* what, const LatencyStats& s) {
    if (s.count == 0) {
      snprintf(line, sizeof(line), "%s: no matched frames\n", what);
    } else {
      snprintf(line, sizeof(line), "%s: %d frames, median %.1f ms, p95 %.1f ms, p99 %.1f ms, max %.1f ms\n",
               what, s.count, s.median_ms, s.p95_ms, s.p99_ms, s.max_ms);
    }
    out << line;
  };
  snprintf(line, sizeof(line), "DEPTH frames: %d\n", summary.depth_frames);
  out << line;
  latency("latency DEPTH -> PEOPLE_VISUAL", summary.depth_to_people_visual);
  latency("latency DEPTH -> PEOPLE_MAP", summary.depth_to_people_map);
  if (!summary.inputs.empty()) {
    int64_t gaps = 0, malformed = 0, errors = 0;
    for (const InputUsage& u : summary.inputs) {
      gaps += u.sequence_gaps;
      malformed += u.dropped_malformed;
      errors += u.handler_errors;
    }
    snprintf(line, sizeof(line),
             "inputs (NODE_STATUS): %zu node channels; %lld messages never handled (sequence gaps: "
             "lost on "
             "the bus, or passed over by a latest-only subscription while its node was busy), %lld "
             "malformed, %lld handler errors\n",
             summary.inputs.size(), static_cast<long long>(gaps), static_cast<long long>(malformed),
             static_cast<long long>(errors));
    out << line;
    for (const InputUsage& u : summary.inputs) {
      if (u.sequence_gaps == 0 && u.dropped_malformed == 0 && u.handler_errors == 0) continue;
      snprintf(line, sizeof(line),
               "    %-28s %-22s received %lld, never handled %lld, malformed %lld, handler errors "
               "%lld\n",
               u.node.c_str(), u.channel.c_str(), static_cast<long long>(u.received),
               static_cast<long long>(u.sequence_gaps), static_cast<long long>(u.dropped_malformed),
               static_cast<long long>(u.handler_errors));
      out << line;
    }
  }
  if (!summary.windows.empty())
    out << "per window: the stack's CPU and every node's inputs, each process's CPU (mean / p95) "
           "and memory at the window's end, each node's own last NODE_STATUS summary\n";
  for (const PerfWindow& w : summary.windows) {
    snprintf(line, sizeof(line),
             "%6.0f-%6.0f s: stack CPU mean %.1f %%, p95 %.1f %% of one core; inputs %lld "
             "received, %lld never handled\n",
             w.start_s, w.end_s, w.stack_cpu_mean_percent, w.stack_cpu_p95_percent,
             static_cast<long long>(w.inputs_received),
             static_cast<long long>(w.input_sequence_gaps));
    out << line;
    for (const WindowUsage& p : w.processes) {
      snprintf(line, sizeof(line), "    %-40s cpu %5.1f / %5.1f %%  rss %7.1f MB%s\n",
               p.command.c_str(), p.mean_cpu_percent, p.p95_cpu_percent, p.rss_end_mb,
               p.excluded ? "  (not counted)" : "");
      out << line;
    }
    for (const auto& [node, text] : w.node_status) out << "    " << node << ": " << text << "\n";
  }
  if (!summary.rss_growth.empty()) {
    snprintf(line, sizeof(line), "memory at %.0f s and at the end:\n", summary.compare_from_s);
    out << line;
    for (const RssGrowth& g : summary.rss_growth) {
      snprintf(line, sizeof(line), "    %-40s %7.1f -> %7.1f MB (%+.1f %%)\n", g.command.c_str(),
               g.rss_then_mb, g.rss_end_mb,
               g.rss_then_mb > 0 ? 100.0 * (g.rss_end_mb / g.rss_then_mb - 1.0) : 0.0);
      out << line;
    }
  }
  if (summary.people_map_restarts > 0) {
    snprintf(line, sizeof(line), "people map restarted %d times: %d of the %d people reported before a restart still there after it\n",
             summary.people_map_restarts, summary.people_kept_across_restarts, summary.people_before_restarts);
    out << line;
  }
  return out.str();
}

}  // namespace logtools
}  // namespace sarmap
