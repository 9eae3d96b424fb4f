#include "log-tools/node_replay.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace sarmap {
namespace logtools {

class NodeReplay::CaptureHandler {
 public:
  explicit CaptureHandler(Sink sink) : sink_(std::move(sink)) {}
  void Handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* data = static_cast<const uint8_t*>(rbuf->data);
    sink_(channel, std::vector<uint8_t>(data, data + rbuf->data_size));
  }

 private:
  Sink sink_;
};

NodeReplay::NodeReplay(common::Node* node) : node_(node) {
  if (node->lcm_url().rfind("memq://", 0) != 0) {
    throw std::invalid_argument("a replay runs its node over memq://, not " + node->lcm_url());
  }
}

NodeReplay::~NodeReplay() = default;

void NodeReplay::Capture(const std::string& channel_regex, Sink sink) {
  captures_.push_back(std::make_unique<CaptureHandler>(std::move(sink)));
  lcm::Subscription* subscription = node_->lcm().subscribe(
      "^(" + channel_regex + ")$", &CaptureHandler::Handle, captures_.back().get());
  // Everything one input causes is handled before the next input: a burst is the most a
  // single event makes, never a backlog.
  if (subscription) subscription->setQueueCapacity(100000);
}

void NodeReplay::Drain() {
  while (node_->lcm().handleTimeout(0) > 0) {
  }
}

void NodeReplay::AdvanceClock(int64_t utime_us) {
  if (now_us_ == 0) {
    // The node's clock starts at the first input: its timers count from there.
    now_us_ = utime_us;
    node_->SetClock([this] { return static_cast<double>(now_us_) * 1e-6; });
  }
  // The clock never goes back: a log's receive times are the recorder's and rise, but a
  // spliced or damaged log must not rewind the node's timers.
  now_us_ = std::max(now_us_, utime_us);
}

void NodeReplay::Inject(const std::string& channel, const std::vector<uint8_t>& data) {
  if (reading_us_ != 0) AdvanceClock(reading_us_);
  node_->lcm().publish(channel, data.data(), static_cast<unsigned>(data.size()));
  Drain();
  node_->SpinOnce(0);  // timers due by the log's time
  Drain();
}

NodeReplay::Stats NodeReplay::Run(const std::string& path,
                                  const std::function<bool(LogEvent*)>& feed,
                                  bool progress) {
  LcmLogReader reader(path);
  Stats stats;
  int next_tenth = 1;
  LogEvent event;
  while (!node_->stopping() && reader.Next(&event)) {
    ++stats.events_read;
    reading_us_ = event.timestamp_us;
    if (feed && !feed(&event)) continue;
    ++stats.events_fed;
    AdvanceClock(event.timestamp_us);
    node_->lcm().publish(event.channel, event.data.data(), static_cast<unsigned>(event.data.size()));
    Drain();
    node_->SpinOnce(0);  // timers due by the log's time
    Drain();
    if (progress && reader.file_size() > 0 &&
        reader.offset() * 10 >= reader.file_size() * next_tenth) {
      std::fprintf(stderr, "  %d %% of %s (%lld events)\n", 10 * next_tenth, path.c_str(),
                   static_cast<long long>(stats.events_read));
      next_tenth = static_cast<int>(reader.offset() * 10 / reader.file_size()) + 1;
    }
  }
  stats.problems = reader.problems();
  return stats;
}

}  // namespace logtools
}  // namespace sarmap
