#pragma once
// Time in sarmap: int64 microseconds ("utime") since the Unix epoch, taken from message
// headers. The wall clock is only for scheduling (timers, status), never for results.

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <utility>
#include <vector>

namespace sarmap {
namespace common {

using Utime = int64_t;

constexpr double UtimeToSeconds(Utime utime) { return static_cast<double>(utime) * 1e-6; }
constexpr Utime SecondsToUtime(double seconds) {
  return static_cast<Utime>(seconds * 1e6 + (seconds >= 0 ? 0.5 : -0.5));
}

// Wall-clock utime, for stamping data at capture by drivers.
Utime WallClockUtime();
// Monotonic seconds, for timers and rate limiting only.
double SteadySeconds();

// A small time-ordered queue in front of an estimator: inputs may arrive out of order (from
// several processes or a replay); they are released in utime order once they are older than
// the newest input by `delay_us`, or on Flush(). An input older than the last released one
// is too late: it is dropped and counted.
template <class T>
class TimeOrderedQueue {
 public:
  explicit TimeOrderedQueue(Utime delay_us) : delay_us_(delay_us) {}

  // Returns false (and counts) when the item is too late to be released in order. Items of
  // different streams (e.g. odometry and scans made from depth frames, which arrive later) are
  // kept in order within each stream only: a late item of one stream is still taken, after
  // newer items of other streams, as long as it is not older than what its own stream released.
  bool Push(Utime utime, T item, int stream = 0) {
    auto released = last_released_.find(stream);
    if (released != last_released_.end() && utime < released->second) {
      ++dropped_late_;
      return false;
    }
    if (utime < newest_) ++reordered_;
    newest_ = std::max(newest_, utime);
    items_.emplace(utime, std::make_pair(stream, std::move(item)));
    return true;
  }

  // Time has reached `utime` on an input that needs no ordering (e.g. POSE kept in a history of
  // its own): without it, the queue's clock would stand still while no other input arrives, and
  // hold what it has.
  void AdvanceTo(Utime utime) { newest_ = std::max(newest_, utime); }

  // Calls `sink(utime, item)` for every item ready for release, oldest first.
  void Release(const std::function<void(Utime, T&)>& sink) { ReleaseUntil(newest_ - delay_us_, sink); }
  void Flush(const std::function<void(Utime, T&)>& sink) { ReleaseUntil(newest_, sink); }

  size_t size() const { return items_.size(); }
  int64_t dropped_late() const { return dropped_late_; }
  int64_t reordered() const { return reordered_; }

 private:
  void ReleaseUntil(Utime until, const std::function<void(Utime, T&)>& sink) {
    while (!items_.empty() && items_.begin()->first <= until) {
      auto node = items_.extract(items_.begin());
      last_released_[node.mapped().first] = node.key();
      sink(node.key(), node.mapped().second);
    }
  }

  Utime delay_us_;
  Utime newest_ = INT64_MIN / 2;
  std::map<int, Utime> last_released_;  // per stream
  int64_t dropped_late_ = 0;
  int64_t reordered_ = 0;
  std::multimap<Utime, std::pair<int, T>> items_;
};

// Keeps a job whose cost grows over a run (rendering a map of the whole graph, saving it) to a
// fraction of the wall time: after a run of d seconds the next may start d (1 / fraction - 1)
// seconds after it ended. Wall-clock scheduling only, like the timers.
class BusyLimiter {
 public:
  explicit BusyLimiter(double fraction) : fraction_(fraction) {}
  bool Allowed(double now_s) const { return now_s >= next_allowed_s_; }
  void Ran(double start_s, double end_s) {
    next_allowed_s_ = end_s + (end_s - start_s) * (1 / fraction_ - 1);
  }

 private:
  double fraction_;
  double next_allowed_s_ = -1e300;
};

}  // namespace common
}  // namespace sarmap
