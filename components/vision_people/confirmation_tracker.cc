#include "vision_people/confirmation_tracker.h"

#include <algorithm>
#include <bitset>
#include <tuple>

namespace sarmap {
namespace vision_people {

ConfirmationTracker::ConfirmationTracker(const ConfirmationOptions& options) : options_(options) {
  common::ValidateOptions(options_);
}

std::vector<ConfirmedPerson> ConfirmationTracker::Update(
    const std::vector<PersonCandidate>& detections) {
  const uint64_t window = options_.n >= 64 ? ~0ull : ((1ull << options_.n) - 1);
  for (Track& t : tracks_) t.history = (t.history << 1) & window;
  // Greedy nearest-neighbour association: closest pairs first, within the gate.
  std::vector<std::tuple<double, size_t, size_t>> pairs;
  const double gate2 = options_.gate_m * options_.gate_m;
  for (size_t d = 0; d < detections.size(); ++d) {
    for (size_t t = 0; t < tracks_.size(); ++t) {
      const double d2 = (detections[d].position_camera - tracks_[t].position).squaredNorm();
      if (d2 <= gate2) pairs.emplace_back(d2, d, t);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> track_of(detections.size(), -1);
  std::vector<bool> track_used(tracks_.size(), false);
  for (const auto& [d2, d, t] : pairs) {
    if (track_of[d] >= 0 || track_used[t]) continue;
    track_of[d] = static_cast<int>(t);
    track_used[t] = true;
  }
  for (size_t d = 0; d < detections.size(); ++d) {
    if (track_of[d] < 0) {
      track_of[d] = static_cast<int>(tracks_.size());
      tracks_.push_back(Track{next_id_++, detections[d].position_camera, 0});
    }
    Track& t = tracks_[track_of[d]];
    t.position = detections[d].position_camera;
    t.history |= 1;
  }
  std::vector<ConfirmedPerson> out;
  for (size_t d = 0; d < detections.size(); ++d) {
    const Track& t = tracks_[track_of[d]];
    const int hits = static_cast<int>(std::bitset<64>(t.history).count());
    if (hits >= options_.k) out.push_back(ConfirmedPerson{t.id, hits, detections[d]});
  }
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [](const Track& t) { return t.history == 0; }),
                tracks_.end());
  return out;
}

}  // namespace vision_people
}  // namespace sarmap
