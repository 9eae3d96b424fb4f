#pragma once
// Replays a log into a node adapter: the class that runs live (its subscriptions, message
// checks, stamp gates and timers) runs offline on the recorded inputs, so a replay is the live
// pipeline by construction. The node runs over memq://, its clock is the log's receive time
// from the first event fed on (common::Node::SetClock), and each event fed is published on the
// node's bus and handled, with everything it causes, before the next is read.
//
//   common::Node node("sarmap-log-speech", logtools::ReplayNodeArgs(node_args));
//   speech::SpeechNode speech(options, &node);
//   logtools::NodeReplay replay(&node);
//   replay.Capture("SPEECH|PEOPLE_AUDIO", [&](const std::string& channel,
//                                             const std::vector<uint8_t>& data) { ... });
//   replay.Run(log_path, [&](logtools::LogEvent* e) { return e->channel == "AUDIO"; });
//   speech.Finish();
//   replay.Drain();

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/node.h"
#include "log-tools/lcm_log_reader.h"

namespace sarmap {
namespace logtools {

// The arguments of the node a replay runs: `args` (--bus-key-file: a signed log's bus key, its
// inputs checked and its outputs signed as live) over memq://.
inline common::NodeArgs ReplayNodeArgs(common::NodeArgs args) {
  args.lcm_url = "memq://";
  return args;
}

class NodeReplay {
 public:
  // Throws std::invalid_argument unless `node` runs over memq://.
  explicit NodeReplay(common::Node* node);
  ~NodeReplay();
  NodeReplay(const NodeReplay&) = delete;
  NodeReplay& operator=(const NodeReplay&) = delete;

  using Sink = std::function<void(const std::string& channel, const std::vector<uint8_t>& data)>;
  // What the node publishes on channels matching `channel_regex` (anchored) goes to `sink`, in
  // the order published, during the event that caused it (now_us() is that event's time).
  void Capture(const std::string& channel_regex, Sink sink);

  struct Stats {
    int64_t events_read = 0;
    int64_t events_fed = 0;
    std::vector<LogProblem> problems;  // damage the tolerant reader read past
  };
  // Reads `path` (LcmLogReader: past damage) and feeds every event `feed` accepts (every event
  // when `feed` is empty; `feed` may also copy or count it, or rewrite its data, e.g. a pose
  // replaced by the truth). Stops early on SIGINT/SIGTERM.
  // With `progress`, a line per tenth of the file on stderr. Throws std::runtime_error when the
  // file cannot be opened.
  Stats Run(const std::string& path, const std::function<bool(LogEvent*)>& feed,
            bool progress = true);
  // Handles everything pending on the bus (e.g. after the adapter's Finish()).
  void Drain();
  // Publishes `data` on `channel` at the present log time (that of the event being read) and
  // handles it, as an event fed: for inputs that are not in the log (e.g. poses from a file), or
  // an event handled inside `feed` (e.g. to time it), from inside `feed`.
  void Inject(const std::string& channel, const std::vector<uint8_t>& data);

  // Receive time of the event being fed, us (0 before the first).
  int64_t now_us() const { return now_us_; }

 private:
  class CaptureHandler;

  // Starts the node's clock at the first call; never moves it back.
  void AdvanceClock(int64_t utime_us);

  common::Node* node_;
  int64_t now_us_ = 0;
  int64_t reading_us_ = 0;  // receive time of the event being read
  std::vector<std::unique_ptr<CaptureHandler>> captures_;
};

}  // namespace logtools
}  // namespace sarmap
