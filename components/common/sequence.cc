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

}  // namespace common
}  // namespace sarmap
