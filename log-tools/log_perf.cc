// sarmap-log perf LOG: CPU and memory of every process of the stack (from the launcher's
// PM_INFO reports in the log) and the latency from a DEPTH frame to the PEOPLE_VISUAL and
// PEOPLE_MAP updates it causes. With --key, only the PM_INFO reports signed with the
// launcher's key count (a forged report in the log is skipped).
#include <cstdio>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "common/args.h"
#include "common/decode.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/stack_perf.h"
#include "procman/order_auth.h"
#include "sarmap/node_status_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pm_info_t.hpp"

namespace {

std::vector<std::string> SplitComma(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log perf", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log perf",
        "What the stack cost during a recorded mission: mean and 95th-percentile CPU (percent\n"
        "of one core, children included) and peak memory of every process, from the launcher's\n"
        "PM_INFO reports (the deputies sample /proc every second), the total of the robot's stack\n"
        "without the simulator and the logger, and the latency from a DEPTH frame to the\n"
        "PEOPLE_VISUAL and PEOPLE_MAP updates it causes (logger receive times, matched by the\n"
        "frame's capture time); every node's inputs received and never handled, from their\n"
        "NODE_STATUS reports.");
    std::string log, exclude = "sarmap-sim,logger,record";
    std::string depth_channel = "DEPTH", visual_channel = "PEOPLE_VISUAL",
                map_channel = "PEOPLE_MAP", info_channel = "PM_INFO",
                status_channel = "NODE_STATUS";
    parser.AddPositional("LOG", &log, "LCM log recorded while the stack ran under sarmap-procman");
    parser.AddFlag("--exclude", &exclude, "comma-separated substrings of commands not counted in the stack total");
    parser.AddFlag("--depth-channel", &depth_channel, "channel of the depth frames");
    parser.AddFlag("--visual-channel", &visual_channel, "channel of the visual detections");
    parser.AddFlag("--map-channel", &map_channel, "channel of the people map");
    parser.AddFlag("--info-channel", &info_channel, "channel of the launcher's deputy reports");
    parser.AddFlag("--status-channel", &status_channel,
                   "channel of the nodes' health reports (inputs received and never handled)");
    std::string key_path;
    parser.AddFlag("--key", &key_path,
                   "the launcher's key file: only deputy reports signed with it are counted "
                   "(without: every report, unverified)");
    double period_s = 0.0, compare_from_s = 3600.0;
    std::string period_csv;
    parser.AddFlag("--period", &period_s,
                   "long missions: also each process's CPU (mean, p95) and memory at the end of "
                   "every this many seconds, and the stack's CPU per window (0: off)");
    parser.AddFlag("--compare-from", &compare_from_s,
                   "with --period: each process's memory this many seconds after the first report "
                   "against its memory at the end");
    parser.AddFlag("--period-csv", &period_csv,
                   "with --period: write the windows to this CSV file (window start and end in s, "
                   "process, samples, CPU mean and p95 in percent of one core, memory at the "
                   "window's end in MB)");
    std::string bus_key_path;
    parser.AddFlag("--bus-key-file", &bus_key_path,
                   "the bus key of a signed bus (common/bus_auth.h): only messages signed with it "
                   "count");
    if (!parser.Parse(argc, argv)) return 0;
    if (!(period_s >= 0) || !(compare_from_s >= 0))
      throw std::invalid_argument("--period and --compare-from must be >= 0 seconds");
    if (!period_csv.empty() && period_s <= 0)
      throw std::invalid_argument("--period-csv needs --period");
    std::optional<sarmap::procman::Key> key;
    if (!key_path.empty()) key = sarmap::procman::LoadKeyFile(key_path);

    sarmap::logtools::LcmLogReader reader(log);
    sarmap::logtools::StackPerf perf(SplitComma(exclude));
    perf.SetPeriod(period_s, compare_from_s);
    sarmap::logtools::LogEvent event;
    // A hostile publisher's datagrams are in the log too (lcm_log_reader.h).
    sarmap::logtools::LogMessageFilter filter;
    if (!bus_key_path.empty()) filter.SetBusKey(sarmap::common::LoadAuthKeyFile(bus_key_path));
    int64_t bad_info = 0, unsigned_info = 0, events = 0;
    int64_t next_report = 64 << 20;
    while (reader.Next(&event)) {
      ++events;
      if (reader.offset() > next_report) {
        fprintf(stderr, "\r  read %.0f%% ...", 100.0 * reader.offset() / std::max<int64_t>(1, reader.file_size()));
        next_report += 64 << 20;
      }
      if (!filter.Accept(event)) continue;
      if (event.channel == info_channel) {
        sarmap::pm_info_t info;
        if (!sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &info)) {
          ++bad_info;
          continue;
        }
        if (key && !sarmap::procman::SignatureValid(*key, info)) {
          ++unsigned_info;
          continue;
        }
        perf.AddMachineLoad(info.cpu_load);
        for (const auto& c : info.commands) {
          perf.AddCommandSample(info.deputy_id, c.command_id,
                                c.state == sarmap::pm_command_status_t::STATE_RUNNING,
                                c.cpu_percent, c.rss_bytes, c.restart_count, event.timestamp_us);
        }
        continue;
      }
      if (event.channel == status_channel) {
        sarmap::node_status_t status;
        if (sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &status)) {
          perf.AddNodeStatusText(status.node_name, status.message, event.timestamp_us);
          for (const auto& c : status.channels)
            perf.AddNodeInput(status.node_name, status.pid, c.channel, c.received,
                              c.dropped_malformed, c.handler_errors, c.sequence_gaps,
                              event.timestamp_us);
        }
        continue;
      }
      if (event.channel == map_channel) {
        sarmap::people_map_t map;
        if (sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &map)) {
          std::vector<std::array<double, 2>> xy;
          for (const auto& p : map.people) xy.push_back({p.position_m[0], p.position_m[1]});
          perf.AddPeopleMapSnapshot(map.header.seq, xy);
        }
      }
      int64_t utime, seq;
      if (!sarmap::logtools::ReadSarmapHeader(event.data, &utime, &seq)) continue;
      if (event.channel == depth_channel) perf.AddDepthFrame(utime, event.timestamp_us);
      if (event.channel == visual_channel) {
        sarmap::people_detections_t seen;
        const bool ok = sarmap::common::DecodeMessage(event.data.data(), event.data.size(), &seen);
        perf.AddPeopleVisual(utime, event.timestamp_us, ok ? seen.num_detections : 0);
      }
      if (event.channel == map_channel) perf.AddPeopleMap(utime, event.timestamp_us);
    }
    if (next_report > (64 << 20)) fprintf(stderr, "\r                 \r");
    for (const auto& p : reader.problems()) {
      fprintf(stderr, "warning: the log breaks at byte %lld: %s\n", static_cast<long long>(p.file_offset),
              p.what.c_str());
    }
    if (bad_info > 0)
      fprintf(stderr, "warning: %lld undecodable %s messages skipped\n",
              static_cast<long long>(bad_info), info_channel.c_str());
    if (key) {
      fprintf(stderr, "%lld %s reports not signed with the key skipped\n",
              static_cast<long long>(unsigned_info), info_channel.c_str());
    } else {
      fprintf(stderr, "%s reports taken unverified (--key checks their signatures)\n",
              info_channel.c_str());
    }
    if (!filter.Summary().empty()) fprintf(stderr, "%s\n", filter.Summary().c_str());
    printf("log %s: %lld events\n", log.c_str(), static_cast<long long>(events));
    const sarmap::logtools::StackPerfSummary summary = perf.Summarise();
    fputs(sarmap::logtools::StackPerfText(summary).c_str(), stdout);
    if (!period_csv.empty()) {
      FILE* csv = fopen(period_csv.c_str(), "w");
      if (!csv) throw std::runtime_error("cannot write " + period_csv);
      fprintf(
          csv,
          "start_s,end_s,process,samples,cpu_mean_percent,cpu_p95_percent,rss_end_mb,counted\n");
      for (const auto& w : summary.windows) {
        fprintf(csv, "%.0f,%.0f,stack,,%.2f,%.2f,,1\n", w.start_s, w.end_s,
                w.stack_cpu_mean_percent, w.stack_cpu_p95_percent);
        for (const auto& p : w.processes)
          fprintf(csv, "%.0f,%.0f,%s,%d,%.2f,%.2f,%.2f,%d\n", w.start_s, w.end_s, p.command.c_str(),
                  p.samples, p.mean_cpu_percent, p.p95_cpu_percent, p.rss_end_mb,
                  p.excluded ? 0 : 1);
      }
      const bool ok = fclose(csv) == 0;
      if (!ok) throw std::runtime_error("cannot write " + period_csv);
      fprintf(stderr, "wrote %s\n", period_csv.c_str());
    }
    return 0;
  });
}
