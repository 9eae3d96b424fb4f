#pragma once
// Multi-frame confirmation: a person is reported once it was detected in at least k of the
// last n frames, tracked by nearest neighbour in 3D (camera frame). A false victim costs a
// rescue team time, so single-frame detections are held back.

#include <cstdint>
#include <vector>

#include "common/options.h"
#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

struct ConfirmationOptions {
  int k = 3;             // detections needed ...
  int n = 5;             // ... in this many most recent frames
  double gate_m = 0.5;   // largest 3D jump between frames for the same track
  template <class V>
  void Visit(V& v) {
    v("k", k, "frames with a detection needed to report a person", InRange(1, n));
    v("n", n, "window of most recent frames (k of n)", InRange(1, 62));
    v("gate_m", gate_m, "nearest-neighbour association gate in 3D", Positive());
  }
};

struct ConfirmedPerson {
  int64_t track_id = -1;
  int hits = 0;  // detections in the window
  PersonCandidate person;
};

class ConfirmationTracker {
 public:
  explicit ConfirmationTracker(const ConfirmationOptions& options);
  // One frame's detections in; the confirmed ones (detected in this frame and in >= k of the
  // last n frames) out.
  std::vector<ConfirmedPerson> Update(const std::vector<PersonCandidate>& detections);
  int num_tracks() const { return static_cast<int>(tracks_.size()); }
  void Reset() { tracks_.clear(); }

 private:
  struct Track {
    int64_t id;
    Eigen::Vector3d position;
    uint64_t history;  // bit 0: this frame
  };
  ConfirmationOptions options_;
  std::vector<Track> tracks_;
  int64_t next_id_ = 1;
};

}  // namespace vision_people
}  // namespace sarmap
