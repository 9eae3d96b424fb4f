#pragma once
// Gap accounting from header.seq: every publisher numbers its messages per channel, so a
// receiver can tell lost messages (gaps) from reordered or repeated ones, and notice a
// publisher restart (seq back at 0).

#include <cstdint>
#include <map>
#include <string>

namespace sarmap {
namespace common {

class SequenceTracker {
 public:
  // Records one received seq. Returns the number of messages missed just before it.
  int64_t Observe(int64_t seq);

  int64_t received() const { return received_; }
  int64_t gaps() const { return gaps_; }            // messages never seen
  int64_t reordered() const { return reordered_; }  // older than the newest seen
  int64_t restarts() const { return restarts_; }    // publisher started counting again

 private:
  bool started_ = false;
  int64_t last_ = 0;
  int64_t received_ = 0;
  int64_t gaps_ = 0;
  int64_t reordered_ = 0;
  int64_t restarts_ = 0;
};

// The sequences of a channel that several publishers share, one tracker per publisher: each
// numbers its own messages, so one tracker for all would read another publisher's lower number as
// a late message and its higher one as a gap (every SLAM client's anchor requests, every node's
// NODE_STATUS). The counts are the sums over publishers. Publishers beyond kMaxPublishers share
// the tracker of "", so a stream of made-up names cannot grow it without bound.
class PublisherSequences {
 public:
  static constexpr size_t kMaxPublishers = 64;
  // As SequenceTracker::Observe, on `publisher`'s own sequence ("" for a channel's only one).
  int64_t Observe(const std::string& publisher, int64_t seq);

  int64_t received() const { return Sum(&SequenceTracker::received); }
  int64_t gaps() const { return Sum(&SequenceTracker::gaps); }
  int64_t reordered() const { return Sum(&SequenceTracker::reordered); }
  int64_t restarts() const { return Sum(&SequenceTracker::restarts); }
  size_t publishers() const { return trackers_.size(); }

 private:
  int64_t Sum(int64_t (SequenceTracker::*count)() const) const;
  std::map<std::string, SequenceTracker> trackers_;
};

}  // namespace common
}  // namespace sarmap
