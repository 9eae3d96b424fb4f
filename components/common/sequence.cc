#include "common/sequence.h"

namespace sarmap {
namespace common {

int64_t SequenceTracker::Observe(int64_t seq) {
  ++received_;
  if (!started_) {
    started_ = true;
    last_ = seq;
    return 0;
  }
  if (seq == last_ + 1) {
    last_ = seq;
    return 0;
  }
  if (seq > last_ + 1) {
    const int64_t missed = seq - last_ - 1;
    gaps_ += missed;
    last_ = seq;
    return missed;
  }
  // seq <= last_: either a late (reordered/duplicate) message or a restarted publisher.
  // Publishers count from 0, so seq 0 after others means the publisher restarted.
  if (seq == 0) {
    ++restarts_;
    last_ = seq;
    return 0;
  }
  ++reordered_;
  if (gaps_ > 0) --gaps_;  // it was counted as missing when the jump happened
  return 0;
}

int64_t PublisherSequences::Observe(const std::string& publisher, int64_t seq) {
  auto it = trackers_.find(publisher);
  if (it == trackers_.end()) {
    const bool room = trackers_.size() + 1 < kMaxPublishers;  // one place stays for ""
    it = trackers_.try_emplace(room ? publisher : std::string()).first;
  }
  return it->second.Observe(seq);
}

int64_t PublisherSequences::Sum(int64_t (SequenceTracker::*count)() const) const {
  int64_t total = 0;
  for (const auto& [publisher, tracker] : trackers_) total += (tracker.*count)();
  return total;
}

}  // namespace common
}  // namespace sarmap
