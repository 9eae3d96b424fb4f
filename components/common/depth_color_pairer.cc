#include "common/depth_color_pairer.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace sarmap {
namespace common {
namespace {
constexpr size_t kMaxRecentColor = 10;
constexpr int64_t kRestartJumpUs = 1000000;  // depth time going back more: a restart
}  // namespace

DepthColorPairer::DepthColorPairer(const DepthColorPairing& pairing)
    : pairing_(pairing),
      max_pair_dt_us_(std::llround(pairing.max_pair_dt_s * 1e6)),
      color_wait_us_(std::llround(pairing.color_wait_s * 1e6)) {
  pairing_.max_pending = std::max(1, pairing_.max_pending);
}

int64_t DepthColorPairer::total_warnings() const {
  int64_t n = 0;
  for (const auto& w : warnings_) n += w.second;
  return n;
}

void DepthColorPairer::Warn(const std::string& kind, const std::string& text) {
  ++warnings_[kind];
  last_warning_ = kind + ": " + text;
}

void DepthColorPairer::AddDepth(const sarmap::image_t& depth, std::vector<Pair>* ready) {
  const int64_t t = depth.header.utime;
  if (have_depth_ && t <= last_depth_us_) {
    if (last_depth_us_ - t <= kRestartJumpUs) {
      Warn("depth_out_of_order", "depth at " + std::to_string(t) +
                                     " us is not after the previous one at " +
                                     std::to_string(last_depth_us_) + " us");
      return;
    }
    // Time went far back: a log replayed again, a restarted camera. Start over, keeping the
    // colour images that may belong to this depth.
    Warn("time_restart", "depth time went back from " + std::to_string(last_depth_us_) + " to " +
                             std::to_string(t) + " us");
    pending_depth_.clear();
    recent_color_.erase(std::remove_if(recent_color_.begin(), recent_color_.end(),
                                       [&](const sarmap::image_t& c) {
                                         return c.header.utime > t + color_wait_us_;
                                       }),
                        recent_color_.end());
    now_us_ = t;
    for (const auto& c : recent_color_) now_us_ = std::max(now_us_, c.header.utime);
  }
  have_depth_ = true;
  last_depth_us_ = t;
  now_us_ = std::max(now_us_, t);
  if (!pairing_.use_color) {
    ready->push_back(Pair{depth, false, {}});
    return;
  }
  pending_depth_.push_back(depth);
  while (pending_depth_.size() > static_cast<size_t>(pairing_.max_pending)) {
    ReleaseAlone("depth_backlog", ready);
  }
  Release(now_us_, ready);
}

void DepthColorPairer::AddColor(const sarmap::image_t& color, std::vector<Pair>* ready) {
  if (!pairing_.use_color) return;
  now_us_ = std::max(now_us_, color.header.utime);
  auto at =
      std::upper_bound(recent_color_.begin(), recent_color_.end(), color.header.utime,
                       [](int64_t t, const sarmap::image_t& c) { return t < c.header.utime; });
  recent_color_.insert(at, color);
  while (recent_color_.size() > kMaxRecentColor) recent_color_.pop_front();
  Release(now_us_, ready);
}

void DepthColorPairer::Flush(std::vector<Pair>* ready) {
  if (pending_depth_.empty()) return;
  Release(pending_depth_.back().header.utime + color_wait_us_ + 1, ready);
}

// The oldest waiting depth image goes on without colour (or is dropped, with require_color).
void DepthColorPairer::ReleaseAlone(const char* reason, std::vector<Pair>* ready) {
  sarmap::image_t& depth = pending_depth_.front();
  const std::string t = std::to_string(depth.header.utime);
  if (pairing_.require_color) {
    Warn(reason, "depth at " + t + " us has no colour image within " +
                     std::to_string(max_pair_dt_us_) + " us; dropped");
  } else {
    Warn("no_color", "depth at " + t + " us has no colour image; depth only");
    ready->push_back(Pair{std::move(depth), false, {}});
  }
  pending_depth_.pop_front();
}

void DepthColorPairer::Release(int64_t now_us, std::vector<Pair>* ready) {
  while (!pending_depth_.empty()) {
    const int64_t t = pending_depth_.front().header.utime;
    auto best = recent_color_.end();
    int64_t best_dt = max_pair_dt_us_ + 1;
    for (auto it = recent_color_.begin(); it != recent_color_.end(); ++it) {
      const int64_t dt = std::llabs(it->header.utime - t);
      if (dt < best_dt) {
        best_dt = dt;
        best = it;
      }
    }
    if (best != recent_color_.end()) {
      ready->push_back(Pair{std::move(pending_depth_.front()), true, *best});
      pending_depth_.pop_front();
      continue;
    }
    if (now_us - t <= color_wait_us_) break;  // wait for its colour
    ReleaseAlone("no_color", ready);
  }
  // Colour older than any waiting depth can pair with is dropped. (With none waiting the
  // colour stays, up to kMaxRecentColor: it may belong to the first depth after a restart.)
  while (!pending_depth_.empty() && !recent_color_.empty() &&
         recent_color_.front().header.utime <
             pending_depth_.front().header.utime - max_pair_dt_us_) {
    recent_color_.pop_front();
  }
}

}  // namespace common
}  // namespace sarmap
