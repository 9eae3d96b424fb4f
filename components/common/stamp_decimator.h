#pragma once
// Thinning a sensor stream by its stamps, so that a replay thins it exactly as the live node did.

#include <cstdint>
#include <optional>

#include "common/time.h"

namespace sarmap {
namespace common {

// Keeps a stream to at most `max_rate_hz` items per second of stamps (0: keeps every item). An
// item is taken when it is at least 0.9 / max_rate_hz after the last one taken: the 10 % margin
// absorbs the jitter of camera stamps, so a 30 Hz camera thinned to 15 Hz keeps every second
// frame. A stamp before the last one taken (a replay started over, a clock step back) is taken
// and starts the count again.
class StampDecimator {
 public:
  explicit StampDecimator(double max_rate_hz)
      : min_gap_us_(max_rate_hz > 0 ? SecondsToUtime(0.9 / max_rate_hz) : 0) {}
  bool Take(Utime utime) {
    if (last_taken_ && utime >= *last_taken_ && utime - *last_taken_ < min_gap_us_) {
      ++skipped_;
      return false;
    }
    last_taken_ = utime;
    return true;
  }
  int64_t skipped() const { return skipped_; }

 private:
  Utime min_gap_us_;
  std::optional<Utime> last_taken_;  // none before the first item
  int64_t skipped_ = 0;
};

}  // namespace common
}  // namespace sarmap
