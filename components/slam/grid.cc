#include "slam/grid.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace slam {

RangeData TransformRangeData(const RangeData& data, const Rigid2d& t) {
  const Eigen::Matrix2f r = t.rotation().toRotationMatrix().cast<float>();
  const Eigen::Vector2f tr = t.translation().cast<float>();
  RangeData out;
  out.origin = r * data.origin + tr;
  out.hits.reserve(data.hits.size());
  out.misses.reserve(data.misses.size());
  for (const auto& p : data.hits) out.hits.push_back(r * p + tr);
  for (const auto& p : data.misses) out.misses.push_back(r * p + tr);
  return out;
}

ProbabilityGrid::ProbabilityGrid(double resolution_m, const Eigen::Vector2d& centre_m,
                                 int initial_cells)
    : resolution_(resolution_m), inv_resolution_(1.0 / resolution_m) {
  width_ = height_ = initial_cells;
  corner_ = centre_m - Eigen::Vector2d(0.5 * width_ * resolution_, 0.5 * height_ * resolution_);
  cells_.assign(static_cast<size_t>(width_) * height_, 0.f);
  update_mark_.assign(cells_.size(), 0);
}

void ProbabilityGrid::GrowToInclude(const Eigen::Vector2f& point) {
  const Eigen::Array2i c = CellIndex(point);
  if (Contains(c)) return;
  Unfinish();
  int grow_left = 0, grow_right = 0, grow_down = 0, grow_up = 0;
  // Grow by at least half the current size so growth is amortised.
  if (c.x() < 0) grow_left = std::max(-c.x() + 20, width_ / 2);
  if (c.x() >= width_) grow_right = std::max(c.x() - width_ + 21, width_ / 2);
  if (c.y() < 0) grow_down = std::max(-c.y() + 20, height_ / 2);
  if (c.y() >= height_) grow_up = std::max(c.y() - height_ + 21, height_ / 2);
  const int new_w = width_ + grow_left + grow_right;
  const int new_h = height_ + grow_down + grow_up;
  std::vector<float> cells(static_cast<size_t>(new_w) * new_h, 0.f);
  for (int y = 0; y < height_; ++y) {
    std::copy(cells_.begin() + static_cast<size_t>(y) * width_,
              cells_.begin() + static_cast<size_t>(y + 1) * width_,
              cells.begin() + static_cast<size_t>(y + grow_down) * new_w + grow_left);
  }
  cells_.swap(cells);
  update_mark_.assign(cells_.size(), 0);
  current_mark_ = 1;
  width_ = new_w;
  height_ = new_h;
  corner_ -= Eigen::Vector2d(grow_left * resolution_, grow_down * resolution_);
}

void ProbabilityGrid::ApplyOdds(int index, float odds_factor) {
  float p = cells_[index];
  if (p == 0.f) p = 0.5f;
  const float odds = p / (1.f - p) * odds_factor;
  p = odds / (1.f + odds);
  cells_[index] = std::min(kMaxProbability, std::max(kMinProbability, p));
}

uint16_t ProbabilityGrid::Encode(float p) {
  if (p == 0.f) return 0;
  const float f = (std::min(kMaxProbability, std::max(kMinProbability, p)) - kMinProbability) /
                  (kMaxProbability - kMinProbability);
  return static_cast<uint16_t>(1 + std::lround(f * 32766.f));
}

void ProbabilityGrid::Unfinish() {
  if (!finished_) return;
  cells_.resize(finished_cells_.size());
  for (size_t i = 0; i < cells_.size(); ++i) cells_[i] = Decode(finished_cells_[i]);
  std::vector<uint16_t>().swap(finished_cells_);
  finished_ = false;
}

void ProbabilityGrid::Insert(const RangeData& data, float hit_probability, float miss_probability,
                             float free_from_m) {
  Unfinish();
  if (update_mark_.size() != cells_.size()) {  // released by Finish()
    update_mark_.assign(cells_.size(), 0);
    current_mark_ = 1;
  }
  GrowToInclude(data.origin);
  for (const auto& p : data.hits) GrowToInclude(p);
  for (const auto& p : data.misses) GrowToInclude(p);
  ++current_mark_;
  if (current_mark_ == 0) {
    std::fill(update_mark_.begin(), update_mark_.end(), 0);
    current_mark_ = 1;
  }
  const float hit_odds = hit_probability / (1.f - hit_probability);
  const float miss_odds = miss_probability / (1.f - miss_probability);
  // Hits first, so a cell that is both hit and crossed by a ray counts as a hit.
  for (const auto& p : data.hits) {
    const Eigen::Array2i c = CellIndex(p);
    const int i = c.y() * width_ + c.x();
    if (update_mark_[i] == current_mark_) continue;
    update_mark_[i] = current_mark_;
    ApplyOdds(i, hit_odds);
  }
  // Rays: walk the cells from the origin towards each end point (Amanatides-Woo traversal),
  // excluding the end cell for hits.
  const double free_from_cells2 =
      static_cast<double>(free_from_m) * free_from_m * inv_resolution_ * inv_resolution_;
  // Squared distance from the origin (ox, oy) to the centre of cell (x, y), in cells.
  auto FromOrigin2 = [](int x, int y, double ox, double oy) {
    const double cx = x + 0.5 - ox, cy = y + 0.5 - oy;
    return cx * cx + cy * cy;
  };
  auto cast = [&](const Eigen::Vector2f& end, bool include_end) {
    const double ox = (data.origin.x() - corner_.x()) * inv_resolution_;
    const double oy = (data.origin.y() - corner_.y()) * inv_resolution_;
    const double ex = (end.x() - corner_.x()) * inv_resolution_;
    const double ey = (end.y() - corner_.y()) * inv_resolution_;
    int x = static_cast<int>(std::floor(ox)), y = static_cast<int>(std::floor(oy));
    const int end_x = static_cast<int>(std::floor(ex)), end_y = static_cast<int>(std::floor(ey));
    const double dx = ex - ox, dy = ey - oy;
    const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
    const double t_dx = dx != 0 ? std::abs(1.0 / dx) : 1e300;
    const double t_dy = dy != 0 ? std::abs(1.0 / dy) : 1e300;
    double t_max_x =
        dx != 0 ? (dx > 0 ? (std::floor(ox) + 1 - ox) : (ox - std::floor(ox))) * t_dx : 1e300;
    double t_max_y =
        dy != 0 ? (dy > 0 ? (std::floor(oy) + 1 - oy) : (oy - std::floor(oy))) * t_dy : 1e300;
    const int max_steps = std::abs(end_x - x) + std::abs(end_y - y) + 2;
    for (int s = 0; s < max_steps; ++s) {
      const bool at_end = x == end_x && y == end_y;
      if (at_end && !include_end) break;
      const int i = y * width_ + x;
      if (x >= 0 && y >= 0 && x < width_ && y < height_ && update_mark_[i] != current_mark_ &&
          (free_from_cells2 == 0 || FromOrigin2(x, y, ox, oy) >= free_from_cells2)) {
        update_mark_[i] = current_mark_;
        ApplyOdds(i, miss_odds);
      }
      if (at_end) break;
      if (t_max_x < t_max_y) {
        t_max_x += t_dx;
        x += step_x;
      } else {
        t_max_y += t_dy;
        y += step_y;
      }
    }
  };
  for (const auto& p : data.hits) cast(p, false);
  for (const auto& p : data.misses) cast(p, true);
}

bool ProbabilityGrid::KnownBounds(Eigen::Array2i* min, Eigen::Array2i* max) const {
  *min = Eigen::Array2i(width_, height_);
  *max = Eigen::Array2i(-1, -1);
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      if (RawAt(static_cast<size_t>(y) * width_ + x) == 0.f) continue;
      *min = min->min(Eigen::Array2i(x, y));
      *max = max->max(Eigen::Array2i(x, y));
    }
  }
  return max->x() >= 0;
}

void ProbabilityGrid::Finish() {
  if (finished_) return;
  std::vector<uint32_t>().swap(update_mark_);
  Eigen::Array2i min, max;
  if (!KnownBounds(&min, &max)) {  // nothing known: keep the extent
    min = Eigen::Array2i(0, 0);
    max = Eigen::Array2i(width_ - 1, height_ - 1);
  }
  const int new_w = max.x() - min.x() + 1, new_h = max.y() - min.y() + 1;
  finished_cells_.assign(static_cast<size_t>(new_w) * new_h, 0);
  for (int y = 0; y < new_h; ++y) {
    const float* row = &cells_[static_cast<size_t>(y + min.y()) * width_ + min.x()];
    uint16_t* out = &finished_cells_[static_cast<size_t>(y) * new_w];
    for (int x = 0; x < new_w; ++x) out[x] = Encode(row[x]);
  }
  std::vector<float>().swap(cells_);
  finished_ = true;
  width_ = new_w;
  height_ = new_h;
  corner_ += Eigen::Vector2d(min.x() * resolution_, min.y() * resolution_);
}

void ProbabilityGrid::SetRaw(int width, int height, const Eigen::Vector2d& corner,
                             std::vector<float> cells) {
  Reset(width, height, corner, false);
  cells_ = std::move(cells);
  update_mark_.assign(cells_.size(), 0);
}

void ProbabilityGrid::SetRawFinished(int width, int height, const Eigen::Vector2d& corner,
                                     std::vector<uint16_t> codes) {
  Reset(width, height, corner, true);
  finished_cells_ = std::move(codes);
}

void ProbabilityGrid::Reset(int width, int height, const Eigen::Vector2d& corner, bool finished) {
  width_ = width;
  height_ = height;
  corner_ = corner;
  finished_ = finished;
  std::vector<float>().swap(cells_);
  std::vector<uint16_t>().swap(finished_cells_);
  std::vector<uint32_t>().swap(update_mark_);
  current_mark_ = 1;
}

}  // namespace slam
}  // namespace sarmap
