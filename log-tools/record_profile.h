#pragma once
// A recording profile for long missions: the camera's frames kept at a low rate except around
// the moments someone is seen, the map kept every few seconds, everything else whole.
//
// RGB-D at 30 Hz is about 85 % of a mission log (4.6 MB/s on the simulated lab: 10 GB in 36
// minutes). The thinner holds every message for `hold_s` of receive time before it decides, so
// frames captured before a detection arrives (the detector's latency) can still be kept, and
// writes what it keeps in arrival order with its receive time, so a thinned log is an ordinary
// log: every reader, `lcm-logplayer` and the report take it as they take a whole one.
//
// Frames (`frames.channels`): a frame is kept when
//   - its capture time (header.utime) is within `frames.around_people_s` of a detection's capture
//     time on `frames.people_channel` (a message there with at least one detection) and, with
//     `frames.around_people_frames: processed`, within `frames.pair_tolerance_s` of a capture
//     time a message there carries (a frame the detector looked at, whether it saw anyone: the
//     detector takes 15 of the camera's 30 frames a second, and a replay of it needs those), or
//   - it is the first frame, in arrival order, whose capture time falls in a `1 / frames.rate_hz`
//     bucket (that capture time is chosen), or its capture time is within
//     `frames.pair_tolerance_s` of a chosen one: a depth frame and the colour frame of the same
//     instant are kept together, as the detector pairs them.
// Grids (`grids.channels`): one every `grids.period_s` of receive time.
// The last message of each thinned channel is always kept (the final map, the last frame): when
// it was passed over, it is written at the end with its own receive time.
// A frame whose header cannot be read is kept (the log keeps what was on the bus).

#include <cstdint>
#include <deque>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "common/options.h"
#include "log-tools/lcm_log_reader.h"

namespace sarmap {
namespace logtools {

struct RecordFramesOptions {
  std::string channels = "DEPTH|RGB";
  double rate_hz = 1.0;
  double pair_tolerance_s = 0.025;
  std::string people_channel = "PEOPLE_VISUAL";
  double around_people_s = 2.0;
  std::string around_people_frames = "processed";
  template <class V>
  void Visit(V& v) {
    v("channels", channels, "camera channels kept at a low rate (regular expression, whole name)");
    v("rate_hz", rate_hz, "frames per second kept of each camera channel (by capture time)",
      Positive());
    v("pair_tolerance_s", pair_tolerance_s,
      "a frame within this of a kept capture time is kept too (depth with its colour)",
      NonNegative());
    v("people_channel", people_channel,
      "people_detections_t channel: a message with a detection keeps the frames around it");
    v("around_people_s", around_people_s,
      "frames captured within this of a detection are kept (0: none)", NonNegative());
    v("around_people_frames", around_people_frames,
      "which of them: processed (those the detector looked at: a people_channel message carries "
      "their capture time, with or without a detection) or all",
      OneOf({"processed", "all"}));
  }
  void Validate(common::Validator& check) const {
    check.That(pair_tolerance_s * rate_hz < 0.5, "pair_tolerance_s",
               "must be under half the kept frame period");
  }
};

struct RecordGridsOptions {
  std::string channels = "MAP";
  double period_s = 10.0;
  template <class V>
  void Visit(V& v) {
    v("channels", channels, "grid channels kept at a low rate (regular expression, whole name)");
    v("period_s", period_s, "one grid kept every this many seconds of receive time", Positive());
  }
};

struct RecordProfileOptions {
  RecordFramesOptions frames;
  RecordGridsOptions grids;
  double hold_s = 3.0;
  double max_held_mb = 256;
  template <class V>
  void Visit(V& v) {
    v("frames", frames, "camera frames");
    v("grids", grids, "occupancy grids");
    v("hold_s", hold_s,
      "every message waits this long (receive time) before it is written or dropped; must "
      "cover frames.around_people_s plus the detector's latency",
      NonNegative());
    v("max_held_mb", max_held_mb,
      "messages held above this many MB are decided early (a flood does not fill the memory)",
      Positive());
  }
  void Validate(common::Validator& check) const {
    check.That(hold_s >= frames.around_people_s, "hold_s",
               "must be >= frames.around_people_s (frames before a detection are still held)");
  }
};

// Kept and dropped messages of one channel.
struct ThinCount {
  int64_t kept = 0, dropped = 0;
  int64_t kept_bytes = 0, dropped_bytes = 0;
};

class RecordThinner {
 public:
  // Throws common::OptionsError on an invalid regular expression.
  explicit RecordThinner(const RecordProfileOptions& options);

  // One message as received (its receive time, in microseconds; receive times need not be
  // strictly increasing).
  void Add(LogEvent event);
  // Messages received at least hold_s before `now_utime` (and the oldest, while more than
  // max_held_mb are held), decided, in arrival order: the kept ones are appended to `out`.
  void Release(int64_t now_utime, std::vector<LogEvent>* out);
  // Everything still held (end of the recording), the last message of each thinned channel kept.
  void Finish(std::vector<LogEvent>* out);

  const std::map<std::string, ThinCount>& counts() const { return counts_; }
  size_t held() const { return held_.size(); }
  int64_t held_bytes() const { return held_bytes_; }

 private:
  enum class Kind { kWhole, kFrame, kGrid };
  struct Held {
    LogEvent event;
    Kind kind = Kind::kWhole;
    bool keep = true;            // decided on arrival (frames: chosen or paired; grids: period)
    int64_t capture_utime = -1;  // frames with a readable header
  };
  Kind KindOf(const std::string& channel);
  // Kept for being near a detection (frames.around_people_s, frames.around_people_frames).
  bool NearPeople(int64_t capture_utime) const;
  void Decide(Held* h);
  void Emit(Held&& h, bool keep, std::vector<LogEvent>* out);

  RecordProfileOptions options_;
  std::regex frames_re_, grids_re_;
  std::map<std::string, Kind> kinds_;
  std::deque<Held> held_;
  int64_t held_bytes_ = 0;
  std::set<int64_t> chosen_buckets_;                // frame buckets with a chosen capture time
  std::set<int64_t> chosen_utimes_;                 // the chosen capture times
  std::set<int64_t> people_utimes_;                 // capture times of detections
  std::set<int64_t> processed_utimes_;              // capture times the detector reported on
  std::map<std::string, int64_t> last_grid_utime_;  // receive time of the last grid kept
  std::map<std::string, Held> passed_;              // per thinned channel, the last one dropped
  std::map<std::string, ThinCount> counts_;
};

// Per thinned channel: messages and megabytes kept of those received, one line each.
std::string ThinSummary(const RecordThinner& thinner);

}  // namespace logtools
}  // namespace sarmap
