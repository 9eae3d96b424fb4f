#include "common/stamp_gate.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace common {

StampGate::Verdict StampGate::Check(Utime utime, double receive_s) {
  if (!anchored_) {
    anchored_ = true;
    clock_utime_ = utime;
    clock_receive_s_ = receive_s;
    return Verdict::kAccepted;
  }
  const Utime max_ahead_us = SecondsToUtime(options_.max_ahead_s);
  const Utime max_behind_us = SecondsToUtime(options_.max_behind_s);
  // Receive time never runs backwards on a steady clock; clamp in case callers mix clocks.
  const double elapsed_us = 1e6 * std::max(0.0, receive_s - clock_receive_s_);
  // In double: stamps near the int64 limits must not overflow.
  const double offset_us =
      static_cast<double>(utime) - (static_cast<double>(clock_utime_) + elapsed_us);
  const bool ahead = offset_us > static_cast<double>(max_ahead_us);
  const bool behind = max_behind_us > 0 && offset_us < -static_cast<double>(max_behind_us);
  if (!ahead && !behind) {
    candidate_count_ = 0;
    if (offset_us > 0) {  // ahead of the clock: the clock moves on; behind: it stands
      clock_utime_ = utime;
      clock_receive_s_ = receive_s;
    }
    return Verdict::kAccepted;
  }
  // Does this stamp continue the run of out-of-bound stamps?
  bool continues = false;
  if (candidate_count_ > 0) {
    const double candidate_elapsed_us = 1e6 * std::max(0.0, receive_s - candidate_receive_s_);
    const double step_us =
        static_cast<double>(utime) - (static_cast<double>(candidate_utime_) + candidate_elapsed_us);
    // A clock advances: the same stamp sent again and again continues no run.
    continues = utime > candidate_utime_ && step_us <= static_cast<double>(max_ahead_us) &&
                step_us >= -static_cast<double>(std::max(max_ahead_us, max_behind_us));
  }
  candidate_count_ = continues ? candidate_count_ + 1 : 1;
  if (candidate_count_ == 1) candidate_first_receive_s_ = receive_s;
  candidate_utime_ = utime;
  candidate_receive_s_ = receive_s;
  if (candidate_count_ >= options_.reanchor_count &&
      receive_s - candidate_first_receive_s_ >= options_.reanchor_min_s) {
    candidate_count_ = 0;
    clock_utime_ = utime;
    clock_receive_s_ = receive_s;
    ++reanchors_;
    return Verdict::kReanchored;
  }
  if (ahead) {
    ++dropped_ahead_;
    return Verdict::kAhead;
  }
  ++dropped_behind_;
  return Verdict::kBehind;
}

bool EncodedHeaderUtime(const void* data, int64_t size, Utime* utime) {
  if (data == nullptr || size < 16) return false;
  const auto* b = static_cast<const uint8_t*>(data) + 8;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  *utime = static_cast<Utime>(v);
  return true;
}

bool StampGates::Accept(int stream, Utime utime, double receive_s) {
  if (stream < 0) return true;
  if (static_cast<size_t>(stream) >= gates_.size()) gates_.resize(stream + 1, StampGate(options_));
  StampGate& gate = gates_[stream];
  if (!gate.anchored()) {
    bool any = false;
    double clock_utime = 0;
    for (const StampGate& other : gates_) {
      if (&other == &gate || !other.anchored()) continue;
      clock_utime = any ? std::max(clock_utime, other.ExpectedUtime(receive_s)) : other.ExpectedUtime(receive_s);
      any = true;
    }
    // In double: the other clocks may sit near the int64 limits.
    if (any && std::abs(clock_utime) < 9e18) gate.Anchor(static_cast<Utime>(clock_utime), receive_s);
  }
  return StampGate::Accepted(gate.Check(utime, receive_s));
}

int64_t StampGates::dropped_ahead() const {
  int64_t n = 0;
  for (const auto& g : gates_) n += g.dropped_ahead();
  return n;
}
int64_t StampGates::dropped_behind() const {
  int64_t n = 0;
  for (const auto& g : gates_) n += g.dropped_behind();
  return n;
}
int64_t StampGates::reanchors() const {
  int64_t n = 0;
  for (const auto& g : gates_) n += g.reanchors();
  return n;
}

}  // namespace common
}  // namespace sarmap
