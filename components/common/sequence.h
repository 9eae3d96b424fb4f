#pragma once
// Gap accounting from header.seq: every publisher numbers its messages per channel, so a
// receiver can tell lost messages (gaps) from reordered or repeated ones, and notice a
// publisher restart (seq back at 0).

#include <cstdint>

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

}  // namespace common
}  // namespace sarmap
