#pragma once
// What the running stack cost, read back from a mission log: CPU and memory per process (from
// the launcher's PM_INFO reports, which the deputies sample from /proc every second, children
// included) and the latency from a DEPTH frame to the PEOPLE_VISUAL and PEOPLE_MAP updates it
// causes (from the logger's receive time stamps: every message of the chain carries the capture
// time of the frame in header.utime, so a frame and its consequences are matched exactly).
// Plain C++, no LCM: the tool decodes messages and feeds this.

#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace sarmap {
namespace logtools {

struct ProcessUsage {
  std::string command;            // "deputy/command"
  int samples = 0;                // PM_INFO samples while running
  double mean_cpu_percent = 0.0;  // of one core
  double p95_cpu_percent = 0.0;
  double max_rss_mb = 0.0;
  int restarts = 0;               // restart_count at the end minus at the start
  bool excluded = false;          // not counted in the stack total (e.g. the simulator)
};

// One process in one window of a long mission (StackPerf::SetPeriod).
struct WindowUsage {
  std::string command;
  int samples = 0;
  double mean_cpu_percent = 0.0, p95_cpu_percent = 0.0;
  double rss_end_mb = 0.0;  // its last sample in the window
  bool excluded = false;
};

// One input channel of one node, from its NODE_STATUS reports (each process's last counters,
// summed over the node's processes: a respawned node counts from zero again).
struct InputUsage {
  std::string node, channel;
  int64_t received = 0, dropped_malformed = 0, handler_errors = 0, sequence_gaps = 0;
};

struct PerfWindow {
  double start_s = 0.0, end_s = 0.0;  // from the first launcher report
  // Every node's inputs in the window (NODE_STATUS counters' increments).
  int64_t inputs_received = 0, input_sequence_gaps = 0;  // gaps: never handled
  // The stack's CPU (the processes not excluded, summed per second of reports).
  double stack_cpu_mean_percent = 0.0, stack_cpu_p95_percent = 0.0;
  std::vector<WindowUsage> processes;
  // Each node's own summary (NODE_STATUS message) last reported in the window, by node.
  std::vector<std::pair<std::string, std::string>> node_status;
};

// A process's memory at one time of the mission and at its end.
struct RssGrowth {
  std::string command;
  double rss_then_mb = 0.0, rss_end_mb = 0.0;
};

struct LatencyStats {
  int count = 0;
  double median_ms = 0.0, p95_ms = 0.0, p99_ms = 0.0, max_ms = 0.0;
};

struct StackPerfSummary {
  std::vector<ProcessUsage> processes;  // by command name
  double stack_cpu_percent = 0.0;       // sum of the means of the processes not excluded
  double excluded_cpu_percent = 0.0;
  double machine_load_percent = 0.0;    // mean whole-machine CPU load reported by the deputies (of all cores)
  int depth_frames = 0;
  LatencyStats depth_to_people_visual;
  LatencyStats depth_to_people_map;
  // Restarts of the people map seen in the log (its header.seq starts again from 0), and how many
  // of the people it had reported just before each restart it still reported just after.
  int people_map_restarts = 0;
  int people_before_restarts = 0;
  int people_kept_across_restarts = 0;
  std::vector<InputUsage> inputs;  // by node and channel
  // With SetPeriod: the mission in windows, and each process's memory growth from
  // compare_from_s to the end (empty when the reports end before compare_from_s).
  std::vector<PerfWindow> windows;
  double compare_from_s = 0.0;
  std::vector<RssGrowth> rss_growth;
};

class StackPerf {
 public:
  // Commands whose id contains one of these substrings are reported but not counted in the
  // stack total (default: the simulator and the logger, which are not part of the robot's stack).
  explicit StackPerf(std::vector<std::string> exclude = {"sarmap-sim", "logger", "record"},
                     double keep_radius_m = 0.45);

  // Long missions: also summarise each period_s of reports (period_s > 0), and each process's
  // memory growth from compare_from_s after the first report to the end.
  void SetPeriod(double period_s, double compare_from_s);

  // One command's line of a PM_INFO report received at receive_us (the time matters only with
  // SetPeriod).
  void AddCommandSample(const std::string& deputy, const std::string& command, bool running,
                        double cpu_percent, int64_t rss_bytes, int restart_count,
                        int64_t receive_us = 0);
  void AddMachineLoad(double cpu_load_fraction);
  // A node's own summary of its state (NODE_STATUS message; kept only with SetPeriod).
  void AddNodeStatusText(const std::string& node, const std::string& text, int64_t receive_us);
  // One input channel's counters from a node's NODE_STATUS report (cumulative since that process
  // started), received at receive_us.
  void AddNodeInput(const std::string& node, int32_t pid, const std::string& channel,
                    int64_t received, int64_t dropped_malformed, int64_t handler_errors,
                    int64_t sequence_gaps, int64_t receive_us = 0);
  // A message of the chain: its header.utime (the capture time of the frame it came from)
  // and when the logger received it.
  void AddDepthFrame(int64_t capture_utime, int64_t receive_us);
  // people_seen: detections in it. DEPTH -> PEOPLE_MAP counts only frames with someone seen (the
  // map is also stamped with the times of other inputs, e.g. SOUND_MAP's, 3 s old).
  void AddPeopleVisual(int64_t capture_utime, int64_t receive_us, int people_seen = 1);
  void AddPeopleMap(int64_t capture_utime, int64_t receive_us);
  // A whole PEOPLE_MAP message: its header.seq and the people's map positions (x, y in m).
  // A person counts as kept across a restart when the first map after it has someone within
  // keep_radius_m of where they were. The people map numbers its messages 0, 1, 2, ... from its
  // start: a message that neither continues that count (at most kMaxSeqStep on: lost messages)
  // nor starts it again (seq below kMaxSeqStep) is not its own (forged or damaged, in a log of
  // an attacked bus) and is skipped.
  static constexpr int64_t kMaxSeqStep = 1000;
  void AddPeopleMapSnapshot(int64_t seq, const std::vector<std::array<double, 2>>& people_xy_m);

  StackPerfSummary Summarise() const;

 private:
  struct Sample {
    int64_t receive_us = 0;
    double cpu_percent = 0.0;
    double rss_bytes = 0.0;
  };
  struct Samples {
    std::vector<double> cpu;
    std::vector<Sample> timed;  // with SetPeriod
    double max_rss_bytes = 0;
    int first_restarts = -1, last_restarts = 0;
  };
  struct InputCounters {
    int64_t receive_us = 0;
    int64_t received = 0, dropped_malformed = 0, handler_errors = 0, sequence_gaps = 0;
  };
  // (node, channel, pid) -> its reports in time order (only the last one without SetPeriod).
  std::map<std::tuple<std::string, std::string, int32_t>, std::vector<InputCounters>> inputs_;
  struct StatusText {
    int64_t receive_us = 0;
    std::string text;
  };
  std::map<std::string, std::vector<StatusText>> status_texts_;  // by node, in time order
  bool Excluded(const std::string& command) const;
  void SummariseWindows(StackPerfSummary* out) const;

  double period_s_ = 0.0, compare_from_s_ = 0.0;
  int64_t first_sample_us_ = -1;
  std::vector<std::string> exclude_;
  double keep_radius_m_;
  int64_t last_map_seq_ = -1;
  bool awaiting_first_after_restart_ = false;
  std::vector<std::array<double, 2>> last_map_people_;
  int map_restarts_ = 0, people_before_restarts_ = 0, people_kept_ = 0;
  std::map<std::string, Samples> commands_;
  std::vector<double> machine_load_;
  std::map<int64_t, int64_t> depth_receive_us_;   // capture utime -> receive time
  std::map<int64_t, int64_t> visual_receive_us_;  // first PEOPLE_VISUAL per capture time
  std::set<int64_t> seen_capture_utimes_;         // PEOPLE_VISUAL with someone in it
  std::map<int64_t, int64_t> map_receive_us_;     // first PEOPLE_MAP per capture time
};

// Human-readable table of a summary.
std::string StackPerfText(const StackPerfSummary& summary);

}  // namespace logtools
}  // namespace sarmap
