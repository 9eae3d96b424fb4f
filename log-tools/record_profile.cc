#include "log-tools/record_profile.h"

#include <cmath>
#include <cstdio>
#include <utility>

#include "common/decode.h"
#include "sarmap/people_detections_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

std::regex Compile(const std::string& pattern, const std::string& key) {
  try {
    return std::regex(pattern, std::regex::extended);
  } catch (const std::regex_error& e) {
    throw common::OptionsError(key + ": not a regular expression: '" + pattern + "' (" + e.what() +
                               ")");
  }
}

// Capture times further back than this behind the newest frame released are forgotten.
constexpr int64_t kMemoryUs = 60'000'000;

// Whether `times` holds one within `tolerance_us` of `utime`.
bool AnyWithin(const std::set<int64_t>& times, int64_t utime, int64_t tolerance_us) {
  const auto it = times.lower_bound(utime - tolerance_us);
  return it != times.end() && *it <= utime + tolerance_us;
}

}  // namespace

RecordThinner::RecordThinner(const RecordProfileOptions& options)
    : options_(options),
      frames_re_(Compile(options.frames.channels, "frames.channels")),
      grids_re_(Compile(options.grids.channels, "grids.channels")) {}

RecordThinner::Kind RecordThinner::KindOf(const std::string& channel) {
  const auto it = kinds_.find(channel);
  if (it != kinds_.end()) return it->second;
  Kind kind = Kind::kWhole;
  if (!options_.frames.channels.empty() && std::regex_match(channel, frames_re_)) {
    kind = Kind::kFrame;
  } else if (!options_.grids.channels.empty() && std::regex_match(channel, grids_re_)) {
    kind = Kind::kGrid;
  }
  kinds_.emplace(channel, kind);
  return kind;
}

void RecordThinner::Decide(Held* h) {
  if (h->kind == Kind::kGrid) {
    auto last = last_grid_utime_.find(h->event.channel);
    h->keep = last == last_grid_utime_.end() ||
              h->event.timestamp_us - last->second >= std::llround(options_.grids.period_s * 1e6);
    if (h->keep) last_grid_utime_[h->event.channel] = h->event.timestamp_us;
    return;
  }
  int64_t utime = 0, seq = 0;
  if (!ReadSarmapHeader(h->event.data, &utime, &seq)) {
    h->keep = true;  // unreadable: kept as the bus gave it
    return;
  }
  h->capture_utime = utime;
  // Paired with a chosen capture time (the other camera stream of the same instant).
  const int64_t tol_us = std::llround(options_.frames.pair_tolerance_s * 1e6);
  if (AnyWithin(chosen_utimes_, utime, tol_us)) {
    h->keep = true;
    return;
  }
  // First in its bucket of 1 / rate_hz: its capture time is chosen.
  const int64_t bucket =
      static_cast<int64_t>(std::floor(static_cast<double>(utime) * 1e-6 * options_.frames.rate_hz));
  h->keep = chosen_buckets_.insert(bucket).second;
  if (h->keep) chosen_utimes_.insert(utime);
}

void RecordThinner::Add(LogEvent event) {
  if (event.channel == options_.frames.people_channel) {
    people_detections_t msg;
    if (common::DecodeMessage(event.data.data(), event.data.size(), &msg)) {
      processed_utimes_.insert(msg.header.utime);
      if (!msg.detections.empty()) people_utimes_.insert(msg.header.utime);
    }
  }
  Held h;
  h.kind = KindOf(event.channel);
  h.event = std::move(event);
  if (h.kind != Kind::kWhole) Decide(&h);
  held_bytes_ += static_cast<int64_t>(h.event.data.size());
  held_.push_back(std::move(h));
}

bool RecordThinner::NearPeople(int64_t capture_utime) const {
  if (capture_utime < 0 || options_.frames.around_people_s <= 0) return false;
  const int64_t around_us = std::llround(options_.frames.around_people_s * 1e6);
  if (!AnyWithin(people_utimes_, capture_utime, around_us)) return false;
  if (options_.frames.around_people_frames == "all") return true;
  const int64_t tol_us = std::llround(options_.frames.pair_tolerance_s * 1e6);
  return AnyWithin(processed_utimes_, capture_utime, tol_us);
}

void RecordThinner::Emit(Held&& h, bool keep, std::vector<LogEvent>* out) {
  ThinCount& count = counts_[h.event.channel];
  const int64_t bytes = static_cast<int64_t>(h.event.data.size());
  held_bytes_ -= bytes;
  if (keep) {
    ++count.kept;
    count.kept_bytes += bytes;
    passed_.erase(h.event.channel);
    out->push_back(std::move(h.event));
    return;
  }
  ++count.dropped;
  count.dropped_bytes += bytes;
  passed_[h.event.channel] = std::move(h);
}

void RecordThinner::Release(int64_t now_utime, std::vector<LogEvent>* out) {
  const int64_t hold_us = std::llround(options_.hold_s * 1e6);
  const int64_t max_held_bytes = std::llround(options_.max_held_mb * 1e6);
  int64_t newest_capture = -1;
  while (!held_.empty() && (held_.front().event.timestamp_us <= now_utime - hold_us ||
                            held_bytes_ > max_held_bytes)) {
    Held h = std::move(held_.front());
    held_.pop_front();
    const bool keep = h.keep || (h.kind == Kind::kFrame && NearPeople(h.capture_utime));
    newest_capture = std::max(newest_capture, h.capture_utime);
    Emit(std::move(h), keep, out);
  }
  if (newest_capture < 0) return;
  // Forget capture times no held frame can still be near.
  const int64_t horizon = newest_capture - kMemoryUs;
  people_utimes_.erase(people_utimes_.begin(), people_utimes_.lower_bound(horizon));
  processed_utimes_.erase(processed_utimes_.begin(), processed_utimes_.lower_bound(horizon));
  chosen_utimes_.erase(chosen_utimes_.begin(), chosen_utimes_.lower_bound(horizon));
  const int64_t horizon_bucket = static_cast<int64_t>(
      std::floor(static_cast<double>(horizon) * 1e-6 * options_.frames.rate_hz));
  chosen_buckets_.erase(chosen_buckets_.begin(), chosen_buckets_.lower_bound(horizon_bucket));
}

void RecordThinner::Finish(std::vector<LogEvent>* out) {
  // The last held message of each thinned channel.
  std::map<std::string, size_t> last_index;
  for (size_t i = 0; i < held_.size(); ++i) {
    if (held_[i].kind != Kind::kWhole) last_index[held_[i].event.channel] = i;
  }
  // A channel whose last message was passed over and that has none held: that one, now.
  for (auto& [channel, h] : passed_) {
    if (last_index.count(channel)) continue;
    ThinCount& count = counts_[channel];
    --count.dropped;
    count.dropped_bytes -= static_cast<int64_t>(h.event.data.size());
    ++count.kept;
    count.kept_bytes += static_cast<int64_t>(h.event.data.size());
    out->push_back(std::move(h.event));
  }
  passed_.clear();
  for (size_t i = 0; i < held_.size(); ++i) {
    Held& h = held_[i];
    const auto last = last_index.find(h.event.channel);
    const bool keep = h.keep || (h.kind == Kind::kFrame && NearPeople(h.capture_utime)) ||
                      (last != last_index.end() && last->second == i);
    Emit(std::move(h), keep, out);
  }
  held_.clear();
  passed_.clear();
}

std::string ThinSummary(const RecordThinner& thinner) {
  std::string out;
  for (const auto& [channel, c] : thinner.counts()) {
    if (c.dropped == 0) continue;
    char line[256];
    std::snprintf(line, sizeof(line), "  %-16s kept %lld of %lld messages, %.1f of %.1f MB\n",
                  channel.c_str(), static_cast<long long>(c.kept),
                  static_cast<long long>(c.kept + c.dropped), c.kept_bytes / 1e6,
                  (c.kept_bytes + c.dropped_bytes) / 1e6);
    out += line;
  }
  return out;
}

}  // namespace logtools
}  // namespace sarmap
