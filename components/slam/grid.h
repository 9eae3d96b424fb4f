#pragma once
// A 2D probability grid (the occupancy probability of each cell) that grows as needed.
//
// Cells hold P(occupied) in [p_min, p_max]; 0 means "never observed". An observation updates
// a cell in odds form, odds(p) = p / (1 - p):
//     odds(p') = odds(p) * odds(p_hit)      for a hit  (p_hit  > 0.5)
//     odds(p') = odds(p) * odds(p_miss)     for a miss (p_miss < 0.5)
// starting from p = 0.5 for a new cell, clamped to [p_min, p_max]. Within one scan a cell is
// updated at most once, a hit winning over a miss (so dense rays do not over-count).
//
// A finished grid (Finish(), only read from then on) stores each cell in 16 bits, as
// Cartographer does: 0 for unknown, else v in 1..32767 with
//     p = p_min + (v - 1) * (p_max - p_min) / 32766,
// a step of 2.4e-5 in probability, half the bytes of a float.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "common/transform.h"

namespace sarmap {
namespace slam {

using common::Rigid2d;
using PointCloud = std::vector<Eigen::Vector2f>;

constexpr float kMinProbability = 0.1f;
constexpr float kMaxProbability = 0.9f;

struct RangeData {
  Eigen::Vector2f origin = Eigen::Vector2f::Zero();  // sensor position
  PointCloud hits;                                   // returns
  PointCloud misses;  // end points of no-return rays (free space only)
};

RangeData TransformRangeData(const RangeData& data, const Rigid2d& transform);

class ProbabilityGrid {
 public:
  // `origin` is the map-frame position of the grid's centre cell at creation.
  ProbabilityGrid(double resolution_m, const Eigen::Vector2d& centre_m, int initial_cells = 100);

  double resolution() const { return resolution_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // Map position of the lower-left corner of cell (0, 0).
  const Eigen::Vector2d& corner() const { return corner_; }

  // Cell index of a map point (may be out of bounds).
  Eigen::Array2i CellIndex(const Eigen::Vector2f& point) const {
    return Eigen::Array2i(
        static_cast<int>(std::floor((point.x() - corner_.x()) * inv_resolution_)),
        static_cast<int>(std::floor((point.y() - corner_.y()) * inv_resolution_)));
  }
  bool Contains(const Eigen::Array2i& cell) const {
    return cell.x() >= 0 && cell.y() >= 0 && cell.x() < width_ && cell.y() < height_;
  }
  // Probability, 0 when unknown or outside.
  float Raw(const Eigen::Array2i& cell) const {
    return Contains(cell) ? RawAt(static_cast<size_t>(cell.y()) * width_ + cell.x()) : 0.f;
  }
  // Probability of the cell at row-major index y * width() + x, 0 when unknown.
  float RawAt(size_t index) const {
    return finished_ ? Decode(finished_cells_[index]) : cells_[index];
  }
  // Probability with unknown/outside as kMinProbability (what matchers use).
  float Probability(int x, int y) const {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return kMinProbability;
    const float p = RawAt(static_cast<size_t>(y) * width_ + x);
    return p == 0.f ? kMinProbability : p;
  }
  // The cells as floats in row-major order while the grid is not finished; nullptr after.
  const float* LiveCells() const { return finished_ ? nullptr : cells_.data(); }
  bool finished() const { return finished_; }

  // Inserts range data given in the map frame (hits update to occupied, rays to free). Rays
  // clear only the cells at least free_from_m from the origin (a depth camera sees low objects
  // only from some range on, and its rays pass over them closer in).
  void Insert(const RangeData& data, float hit_probability, float miss_probability,
              float free_from_m = 0.f);

  // Grows the grid so that `point` (map frame) lies inside, with a margin.
  void GrowToInclude(const Eigen::Vector2f& point);

  // Bounding box of known cells [min, max] (inclusive); false if none.
  bool KnownBounds(Eigen::Array2i* min, Eigen::Array2i* max) const;

  // For a grid that is only read from now on: crops it to its known cells (growth leaves up to
  // half the grid unknown), stores them in 16 bits and frees the per-scan update marks; reads
  // change by at most half a 16-bit step (outside and unknown read alike). Inserting again
  // works, at the cost of going back to floats and re-allocating the marks.
  void Finish();

  // Bytes of its cells and update marks (capacity).
  size_t MemoryBytes() const {
    return cells_.capacity() * sizeof(float) + finished_cells_.capacity() * sizeof(uint16_t) +
           update_mark_.capacity() * sizeof(uint32_t);
  }

  // The 16-bit code of a probability (0 for unknown) and back.
  static uint16_t Encode(float p);
  static float Decode(uint16_t v) {
    return v == 0 ? 0.f
                  : kMinProbability + (v - 1) * ((kMaxProbability - kMinProbability) / 32766.f);
  }

  // Raw access for saving and loading: a finished grid's 16-bit codes (nullptr while not
  // finished), and a grid set from floats (not finished) or from codes (finished).
  const uint16_t* FinishedCells() const { return finished_ ? finished_cells_.data() : nullptr; }
  void SetRaw(int width, int height, const Eigen::Vector2d& corner, std::vector<float> cells);
  void SetRawFinished(int width, int height, const Eigen::Vector2d& corner,
                      std::vector<uint16_t> codes);

 private:
  void ApplyOdds(int index, float odds_factor);
  void Unfinish();  // back to float cells, for inserting into a finished grid
  // Empty cells of the given extent, finished or not (SetRaw, SetRawFinished fill them).
  void Reset(int width, int height, const Eigen::Vector2d& corner, bool finished);

  double resolution_, inv_resolution_;
  Eigen::Vector2d corner_;
  int width_ = 0, height_ = 0;
  bool finished_ = false;
  std::vector<float> cells_;              // while not finished
  std::vector<uint16_t> finished_cells_;  // once finished (Encode)
  std::vector<uint32_t> update_mark_;
  uint32_t current_mark_ = 1;
};

}  // namespace slam
}  // namespace sarmap
