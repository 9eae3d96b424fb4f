#pragma once
// Pairs DEPTH and RGB image_t messages by capture time, for every component that takes RGB-D
// frames off the bus (visual odometry, people detection). Only the generated message structs:
// testable without a bus.
//
// A depth image pairs with the colour image closest to it in time within max_pair_dt_s, in
// whichever order the two arrive. Without one it waits until message time (the newest stamp
// seen on either channel) is color_wait_s past it, then goes on alone or, with require_color,
// is dropped ("no_color"). At most max_pending depth images wait; the oldest beyond that is
// released as if its wait were over ("depth_backlog" when it is dropped). Depth older than the
// previous depth is dropped ("depth_out_of_order"), unless it is more than 1 s older: then time
// restarted (a log replayed again, a restarted camera) and pairing starts over ("time_restart").
// With use_color false every depth image is released at once and colour is ignored. Nothing
// throws; every problem is counted by name.

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "sarmap/image_t.hpp"

namespace sarmap {
namespace common {

struct DepthColorPairing {
  bool use_color = true;
  bool require_color = false;
  double max_pair_dt_s = 0.02;
  double color_wait_s = 0.2;
  int max_pending = 8;
};

class DepthColorPairer {
 public:
  struct Pair {
    sarmap::image_t depth;
    bool has_color = false;
    sarmap::image_t color;
  };

  explicit DepthColorPairer(const DepthColorPairing& pairing);

  // Each call may complete pairs; they are appended to `ready` in time order.
  void AddDepth(const sarmap::image_t& depth, std::vector<Pair>* ready);
  void AddColor(const sarmap::image_t& color, std::vector<Pair>* ready);
  // No more messages are coming for now (the bus went quiet): depth images still waiting for
  // their colour are released as if the wait were over.
  void Flush(std::vector<Pair>* ready);
  bool has_pending() const { return !pending_depth_.empty(); }

  // Warning name -> count; the caller adds its own (decoding) warnings through Warn.
  const std::map<std::string, int64_t>& warnings() const { return warnings_; }
  int64_t total_warnings() const;
  const std::string& last_warning() const { return last_warning_; }
  void Warn(const std::string& kind, const std::string& text);

 private:
  // Pairs what can be paired at message time `now_us`; releases what waited long enough.
  void Release(int64_t now_us, std::vector<Pair>* ready);
  void ReleaseAlone(const char* reason, std::vector<Pair>* ready);

  DepthColorPairing pairing_;
  int64_t max_pair_dt_us_;
  int64_t color_wait_us_;
  int64_t now_us_ = 0;
  int64_t last_depth_us_ = 0;
  bool have_depth_ = false;
  std::deque<sarmap::image_t> pending_depth_;
  std::deque<sarmap::image_t> recent_color_;  // time order
  std::map<std::string, int64_t> warnings_;
  std::string last_warning_;
};

// A component's RGB-D frame assembler: pairs DEPTH and RGB messages with a DepthColorPairer and
// decodes each pair into a Frame with Build(); the warnings are the pairer's and Build()'s.
template <class Frame>
class FrameAssemblerBase {
 public:
  explicit FrameAssemblerBase(const DepthColorPairing& pairing) : pairer_(pairing) {}
  virtual ~FrameAssemblerBase() = default;

  // Each call may complete frames; they are appended to `ready` in time order.
  void AddDepth(const sarmap::image_t& depth, std::vector<Frame>* ready) {
    pairer_.AddDepth(depth, &pairs_);
    BuildAll(ready);
  }
  void AddColor(const sarmap::image_t& color, std::vector<Frame>* ready) {
    pairer_.AddColor(color, &pairs_);
    BuildAll(ready);
  }
  // No more messages are coming for now (the bus went quiet): depth frames still waiting for
  // their colour go on as if the wait had timed out (the last frame of a depth-only replay).
  void Flush(std::vector<Frame>* ready) {
    pairer_.Flush(&pairs_);
    BuildAll(ready);
  }
  bool has_pending() const { return pairer_.has_pending(); }

  // Pairs for which `take(depth stamp)` is false are passed over before they are decoded (a
  // node that thins its stream by stamps saves the decoding of every frame it would drop).
  void TakeOnly(std::function<bool(int64_t utime)> take) { take_ = std::move(take); }

  // Warning name -> count.
  const std::map<std::string, int64_t>& warnings() const { return pairer_.warnings(); }
  int64_t total_warnings() const { return pairer_.total_warnings(); }
  // The last warning's text, for logs.
  const std::string& last_warning() const { return pairer_.last_warning(); }

 protected:
  // Decodes one pair into `frame`; false (a warning counted through pairer_.Warn) skips it.
  virtual bool Build(const DepthColorPairer::Pair& pair, Frame* frame) = 0;

  DepthColorPairer pairer_;

 private:
  void BuildAll(std::vector<Frame>* ready) {
    for (const auto& pair : pairs_) {
      if (take_ && !take_(pair.depth.header.utime)) continue;
      Frame frame;
      if (Build(pair, &frame)) ready->push_back(std::move(frame));
    }
    pairs_.clear();
  }

  std::vector<DepthColorPairer::Pair> pairs_;
  std::function<bool(int64_t utime)> take_;
};

}  // namespace common
}  // namespace sarmap
