#pragma once
// StampGate: what a single header.utime may do to a node. Each input stream keeps its own
// clock: a stamp it accepted and the receive time (steady clock) of that message. A new stamp
// is expected near
//   expected = clock_utime + (receive_s - clock_receive_s)
// and is dropped (and counted) when it is more than max_ahead_s ahead of that, or, when
// max_behind_s > 0, more than max_behind_s behind it. An accepted stamp ahead of `expected`
// becomes the clock; one behind it does not, so the clock never runs back: a stream whose
// stamps are data times (a reply stamped with the time of the data it answers, arriving
// seconds after it) keeps its clock, and the next current stamp is not "ahead". Dropped stamps
// are never adopted: one far-future POSE or SCAN cannot move a node's clock. The rule needs no wall
// clock, so it holds on log replay too (a replay faster than real time only moves stamps by one
// message's period between two receive times). A genuine clock step of a whole stream is followed:
// after reanchor_count consecutive dropped stamps that agree with each other (each later than the
// previous one, and within max_ahead_s of it plus the receive time between them) and span at least
// reanchor_min_s of receive time, the stream's clock is re-anchored on the last of them, which is
// accepted. Any accepted stamp in between starts the count again, so a stray stamp mixed into a
// live stream is never followed, and neither is a second publisher interleaved with it (the live
// stream's own messages break every run shorter than reanchor_min_s). A stamp repeated (a replayed
// or forged message sent again and again) is a clock that stands still, not a stream: it never
// re-anchors.
// The first stamp of a stream sets its clock, unless the node already has a clock from another
// stream (StampGates): then the new stream starts on that clock, so a far-future first message
// on a stream nobody has published on yet (a forged one) is dropped like any other.

#include <cstdint>
#include <vector>

#include "common/options.h"
#include "common/time.h"

namespace sarmap {
namespace common {

struct StampGateOptions {
  double max_ahead_s = 5.0;  // stamps further ahead of the stream's clock are dropped
  double max_behind_s =
      0;  // stamps further behind are dropped (0: never; late inputs are the node's)
  int reanchor_count = 5;  // consecutive agreeing out-of-bound stamps that re-anchor the stream
  double reanchor_min_s = 1.0;  // ... received over at least this long, nothing accepted between
  template <class V>
  void Visit(V& v) {
    v("max_ahead_s", max_ahead_s,
      "an input stamped further ahead of its stream's clock (the most advanced accepted stamp + "
      "receive time since) is dropped and counted",
      Positive());
    v("max_behind_s", max_behind_s,
      "an input stamped further behind its stream's clock is dropped and counted (0: never)",
      NonNegative());
    v("reanchor_count", reanchor_count,
      "this many consecutive dropped stamps that agree with each other re-anchor the stream (a "
      "genuine clock step is followed)",
      AtLeast(1));
    v("reanchor_min_s", reanchor_min_s,
      "a re-anchoring run of stamps must span at least this much receive time with no accepted "
      "stamp in it (a live stream is never re-anchored by a second publisher)",
      NonNegative());
  }
};

class StampGate {
 public:
  enum class Verdict { kAccepted, kReanchored, kAhead, kBehind };

  explicit StampGate(const StampGateOptions& options = {}) : options_(options) {}

  // receive_s: steady-clock time the message was received (ReceiveInfo::receive_time_s).
  Verdict Check(Utime utime, double receive_s);
  static bool Accepted(Verdict v) { return v == Verdict::kAccepted || v == Verdict::kReanchored; }

  bool anchored() const { return anchored_; }
  // Sets the stream's clock (for a stream that has no stamp of its own yet).
  void Anchor(Utime utime, double receive_s) {
    anchored_ = true;
    clock_utime_ = utime;
    clock_receive_s_ = receive_s;
  }
  // Where the stream's clock stands at receive_s (anchored streams only).
  double ExpectedUtime(double receive_s) const {
    return static_cast<double>(clock_utime_) + 1e6 * (receive_s - clock_receive_s_);
  }
  // The stamp the clock counts from (received at clock_receive_s).
  Utime clock_utime() const { return clock_utime_; }
  int64_t dropped_ahead() const { return dropped_ahead_; }
  int64_t dropped_behind() const { return dropped_behind_; }
  int64_t dropped() const { return dropped_ahead_ + dropped_behind_; }
  int64_t reanchors() const { return reanchors_; }

 private:
  StampGateOptions options_;
  bool anchored_ = false;
  Utime clock_utime_ = 0;
  double clock_receive_s_ = 0;
  // The run of consecutive out-of-bound stamps that may re-anchor the stream.
  int candidate_count_ = 0;
  Utime candidate_utime_ = 0;
  double candidate_receive_s_ = 0;
  double candidate_first_receive_s_ = 0;
  int64_t dropped_ahead_ = 0;
  int64_t dropped_behind_ = 0;
  int64_t reanchors_ = 0;
};

// header.utime of an encoded sarmap message (every type starts with header_t, right after the
// 8-byte fingerprint), for gating a log's events before decoding them; false when too short.
bool EncodedHeaderUtime(const void* data, int64_t size, Utime* utime);

// A gate per input stream of a node, with one set of counters for NODE_STATUS. A stream's
// first message is checked against the most advanced clock of the node's other streams.
class StampGates {
 public:
  explicit StampGates(const StampGateOptions& options) : options_(options) {}
  // stream: a small index per input (e.g. the channel's position in the node's list).
  bool Accept(int stream, Utime utime, double receive_s);
  int64_t dropped_ahead() const;
  int64_t dropped_behind() const;
  int64_t dropped() const { return dropped_ahead() + dropped_behind(); }
  int64_t reanchors() const;

 private:
  StampGateOptions options_;
  std::vector<StampGate> gates_;
};

}  // namespace common
}  // namespace sarmap
