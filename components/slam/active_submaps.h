#pragma once
// Local SLAM's active submaps (Cartographer's ActiveSubmaps2D): every node is inserted into
// each of them; a new submap starts whenever the newest holds scans_per_submap nodes, and the
// older one then finishes, so two overlap and each finished submap holds 2 * scans_per_submap
// nodes. Scans are matched against the older (fuller) one.
// This class keeps which submaps are active and decides the changes; the submaps themselves
// (grids, nodes) belong to Slam.

#include <vector>

namespace sarmap {
namespace slam {

class ActiveSubmaps {
 public:
  explicit ActiveSubmaps(int scans_per_submap) : scans_per_submap_(scans_per_submap) {}

  bool empty() const { return ids_.empty(); }
  // Oldest first.
  const std::vector<int>& ids() const { return ids_; }
  // The submap scans are matched against: the oldest active one.
  int matching() const { return ids_.front(); }

  // A new submap `id` is active.
  void Add(int id) { ids_.push_back(id); }

  // What follows a node's insertion into every active submap, given how many nodes the newest
  // now holds: the submap that finishes (no longer active; -1 when none) and whether a new
  // submap must start (then Add it).
  struct Change {
    int finished = -1;
    bool start_new = false;
  };
  Change AfterInsertion(int newest_num_inserted) {
    Change change;
    if (newest_num_inserted != scans_per_submap_) return change;
    if (ids_.size() == 2) {
      change.finished = ids_.front();
      ids_.erase(ids_.begin());
    }
    change.start_new = true;
    return change;
  }

  // A saved state's active submaps (oldest first).
  void Restore(std::vector<int> ids) { ids_ = std::move(ids); }

 private:
  int scans_per_submap_;
  std::vector<int> ids_;
};

}  // namespace slam
}  // namespace sarmap
