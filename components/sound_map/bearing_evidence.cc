#include "sound_map/bearing_evidence.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace sarmap {
namespace sound_map {

void BearingEvidence::Add(const Ray& ray) {
  if (!std::isfinite(ray.azimuth_rad) || !std::isfinite(ray.sigma_rad) || !(ray.sigma_rad > 0) ||
      !ray.node_from_base.vec().allFinite())
    return;
  if (ray.heard) {  // heard directions: the oldest go first
    heard_.push_back(ray);
    const size_t cap = static_cast<size_t>(options_.max_rays);
    if (heard_.size() > cap + cap / 10)
      heard_.erase(heard_.begin(), heard_.begin() + (heard_.size() - cap));
    return;
  }
  rays_.push_back(ray);
  rays_.back().weight = 1;
  if (rays_.size() <= static_cast<size_t>(options_.max_rays)) return;
  // Over the limit: rays heard from within half a metre of each other in the same direction
  // (bins of half the DOA std floor) and of the same class are merged into the oldest of them,
  // which then stands for all (its weight): a source heard long ago keeps its evidence. Beyond
  // 90 % of the limit after that, the oldest rays go (so this runs once per tenth of the limit).
  std::vector<Ray> rays;
  std::vector<Cache> cache;
  const size_t cached = std::min(cache_.size(), rays_.size());  // placed at the last solve
  const double bearing_bin = 0.5 * options_.sigma_floor_deg * M_PI / 180;
  std::map<std::tuple<int64_t, int64_t, int64_t, int>, size_t> bins;  // -> index in rays
  rays.reserve(rays_.size());
  for (size_t i = 0; i < rays_.size(); ++i) {
    if (i < cached && !cache_[i].cells.empty()) {
      const Placed& p = cache_[i].placed;
      const auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.origin.x() / 0.5)),
                                       static_cast<int64_t>(std::floor(p.origin.y() / 0.5)),
                                       static_cast<int64_t>(std::floor(p.bearing / bearing_bin)),
                                       rays_[i].sound_class);
      auto it = bins.find(key);
      if (it != bins.end()) {
        rays[it->second].weight += rays_[i].weight;
        continue;
      }
      bins[key] = rays.size();
    }
    rays.push_back(rays_[i]);
    if (i < cached) cache.push_back(std::move(cache_[i]));
  }
  const size_t keep = static_cast<size_t>(options_.max_rays) * 9 / 10;
  if (rays.size() > keep) {
    const size_t drop = rays.size() - keep;
    rays.erase(rays.begin(), rays.begin() + drop);
    cache.erase(cache.begin(), cache.begin() + std::min(drop, cache.size()));
  }
  rays_ = std::move(rays);
  cache_ = std::move(cache);
}

bool BearingEvidence::Place(const Ray& r, const std::map<int64_t, Pose2>& node_poses,
                            Placed* p) const {
  Pose2 base = r.node_from_base;
  if (r.node >= 0) {
    auto it = node_poses.find(r.node);
    if (it == node_poses.end()) return false;
    base = Compose(it->second, r.node_from_base);
  }
  const double pose[3] = {base.x, base.y, base.yaw};
  double o[2];
  ArrayOrigin(pose, mount_, o);
  p->origin = Eigen::Vector2d(o[0], o[1]);
  p->bearing = WrapAngle(base.yaw + mount_.yaw_rad + r.azimuth_rad);
  p->sigma = std::max(r.sigma_rad, options_.sigma_floor_deg * M_PI / 180);
  return true;
}

void BearingEvidence::Cover(const Placed& p, std::vector<Cell>* cells) const {
  // Walk the wedge in steps of half a cell along and across the ray and keep the likelihood of
  // each cell's centre once (a cell is met by neighbouring steps: the list is sorted and
  // de-duplicated).
  cells->clear();
  const double cell = options_.cell_m, step = 0.5 * cell;
  const Eigen::Vector2d dir(std::cos(p.bearing), std::sin(p.bearing));
  const Eigen::Vector2d normal(-dir.y(), dir.x());
  const double half_angle = std::min(options_.window_sigmas * p.sigma, 0.5 * M_PI - 0.01);
  const double norm = 1.0 / (std::sqrt(2 * M_PI) * p.sigma);
  std::vector<int64_t> keys;
  for (double d = options_.min_range_m; d <= options_.max_range_m; d += step) {
    const double half_width = d * std::tan(half_angle);
    for (double u = -half_width; u <= half_width; u += step) {
      const Eigen::Vector2d q = p.origin + d * dir + u * normal;
      keys.push_back(Key(static_cast<int32_t>(std::floor(q.x() / cell)),
                         static_cast<int32_t>(std::floor(q.y() / cell))));
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  for (int64_t key : keys) {
    const int32_t ix = KeyX(key), iy = KeyY(key);
    const Eigen::Vector2d to = Eigen::Vector2d((ix + 0.5) * cell, (iy + 0.5) * cell) - p.origin;
    const double range = to.norm();
    if (range < options_.min_range_m || range > options_.max_range_m) continue;
    const double e = WrapAngle(std::atan2(to.y(), to.x()) - p.bearing) / p.sigma;
    if (std::abs(e) > options_.window_sigmas) continue;
    cells->push_back(Cell{ix, iy, static_cast<float>(norm * std::exp(-0.5 * e * e))});
  }
}

std::vector<BearingEvidence::Source> BearingEvidence::Solve(
    const std::map<int64_t, Pose2>& node_poses, const Eigen::Vector2d* min_m,
    const Eigen::Vector2d* max_m) {
  std::vector<Source> out;
  if (!options_.enabled || rays_.empty()) return out;
  cache_.resize(rays_.size());
  // Place every ray with its node's latest pose; a ray that moved recomputes its cells.
  const double cell = options_.cell_m;
  std::vector<size_t> use;  // rays placed
  int32_t x0 = INT32_MAX, y0 = INT32_MAX, x1 = INT32_MIN, y1 = INT32_MIN;
  for (size_t i = 0; i < rays_.size(); ++i) {
    Placed p;
    if (!Place(rays_[i], node_poses, &p)) continue;
    Cache& c = cache_[i];
    if (!((c.placed.origin - p.origin).norm() < 0.25 * cell) ||
        !(std::abs(WrapAngle(c.placed.bearing - p.bearing)) < 0.1 * p.sigma) ||
        c.placed.sigma != p.sigma) {
      c.placed = p;
      Cover(p, &c.cells);
    }
    if (c.cells.empty()) continue;
    use.push_back(i);
    for (const Cell& e : c.cells) {
      x0 = std::min(x0, e.ix), x1 = std::max(x1, e.ix);
      y0 = std::min(y0, e.iy), y1 = std::max(y1, e.iy);
    }
  }
  if (use.empty()) return out;
  // The grid: the cells the rays cover (not clipped to the site: a source beyond it would be
  // drawn onto its edge).
  if (x1 < x0 || y1 < y0) return out;
  const int nx = x1 - x0 + 1, ny = y1 - y0 + 1;
  if (static_cast<int64_t>(nx) * ny > 4000000) return out;  // a site of more than 160,000 m^2
  const auto index = [&](const Cell& e) {
    return (e.ix < x0 || e.ix > x1 || e.iy < y0 || e.iy > y1) ? -1 : (e.iy - y0) * nx + (e.ix - x0);
  };
  const auto centre = [&](int c) {
    return Eigen::Vector2d((x0 + c % nx + 0.5) * cell, (y0 + c / nx + 0.5) * cell);
  };
  const size_t n = use.size();

  // The rays' cells as flat arrays of grid indices and likelihoods (cells outside the grid
  // dropped), ray k's from offset[k] to offset[k + 1].
  std::vector<int32_t> flat_cell;
  std::vector<float> flat_a;
  std::vector<size_t> offset(n + 1, 0);
  for (size_t k = 0; k < n; ++k) {
    for (const Cell& e : cache_[use[k]].cells) {
      const int c = index(e);
      if (c < 0) continue;
      flat_cell.push_back(c);
      flat_a.push_back(e.a);
    }
    offset[k + 1] = flat_cell.size();
  }
  // EM on the mixture weights over the cells any ray covers, and clutter, from uniform weights.
  // A fixed number of iterations: EM run to convergence puts spikes wherever two rays cross;
  // stopped early, mass gathers only where many do.
  std::vector<double> weight(static_cast<size_t>(nx) * ny, 0.0), next(weight.size(), 0.0);
  std::vector<int32_t> cells;
  for (int32_t c : flat_cell)
    if (weight[c] == 0) {
      weight[c] = 1;
      cells.push_back(c);
    }
  if (cells.empty()) return out;
  double clutter = 0.5;
  for (int32_t c : cells) weight[c] = 0.5 / static_cast<double>(cells.size());
  const double clutter_a = 1.0 / (2 * M_PI);
  std::vector<double> evidence(n, 0.0);  // p(r)
  double total_weight = 0;               // rays' worth
  for (size_t k = 0; k < n; ++k) total_weight += rays_[use[k]].weight;
  const auto likelihoods = [&] {
    for (size_t k = 0; k < n; ++k) {
      double p = clutter * clutter_a;
      for (size_t j = offset[k]; j < offset[k + 1]; ++j) p += weight[flat_cell[j]] * flat_a[j];
      evidence[k] = p;
    }
  };
  for (int it = 0; it < options_.iterations; ++it) {
    likelihoods();
    double next_clutter = 0;
    for (size_t k = 0; k < n; ++k) {
      const double inv = rays_[use[k]].weight / evidence[k];
      for (size_t j = offset[k]; j < offset[k + 1]; ++j) next[flat_cell[j]] += flat_a[j] * inv;
      next_clutter += clutter * clutter_a * inv;
    }
    const double inv_n = 1.0 / total_weight;
    for (int32_t c : cells) {
      weight[c] *= next[c] * inv_n;
      next[c] = 0;
    }
    clutter = next_clutter * inv_n;
  }
  likelihoods();  // p(r) under the final weights

  // Peaks: mass (rays' worth) within peak_radius_m, greedily, 2 peak radii apart.
  const int reach = static_cast<int>(std::ceil(options_.peak_radius_m / cell));
  std::vector<std::pair<int, int>> disk;
  for (int dy = -reach; dy <= reach; ++dy)
    for (int dx = -reach; dx <= reach; ++dx)
      if (std::hypot(dx, dy) * cell <= options_.peak_radius_m) disk.emplace_back(dx, dy);
  std::vector<std::pair<double, int32_t>> mass;
  for (int32_t c : cells) {
    if (weight[c] * total_weight < 1e-3) continue;
    double m = 0;
    const int cx = c % nx, cy = c / nx;
    for (const auto& [dx, dy] : disk) {
      const int x = cx + dx, y = cy + dy;
      if (x >= 0 && y >= 0 && x < nx && y < ny) m += weight[y * nx + x];
    }
    mass.emplace_back(m * total_weight, c);
  }
  std::sort(mass.begin(), mass.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<int> owner(weight.size(), -1);  // the source whose disk a cell is in
  std::vector<int32_t> peak_cells;
  for (const auto& [m, c] : mass) {
    if (m < options_.min_rays) break;
    const Eigen::Vector2d at = centre(c);
    bool free = true;
    for (int32_t other : peak_cells)
      if ((centre(other) - at).norm() < 2 * options_.peak_radius_m) free = false;
    if (!free) continue;
    const int k = static_cast<int>(peak_cells.size());
    peak_cells.push_back(c);
    const int cx = c % nx, cy = c / nx;
    for (const auto& [dx, dy] : disk) {
      const int x = cx + dx, y = cy + dy;
      if (x >= 0 && y >= 0 && x < nx && y < ny && owner[y * nx + x] < 0) owner[y * nx + x] = k;
    }
  }
  out.resize(peak_cells.size());
  std::vector<double> total(peak_cells.size(), 0.0);
  std::vector<Eigen::Vector2d> sum(peak_cells.size(), Eigen::Vector2d::Zero());
  for (size_t c = 0; c < owner.size(); ++c) {
    if (owner[c] < 0) continue;
    total[owner[c]] += weight[c];
    sum[owner[c]] += weight[c] * centre(static_cast<int>(c));
  }
  for (size_t k = 0; k < out.size(); ++k) {
    out[k].position_m = total[k] > 0 ? Eigen::Vector2d(sum[k] / total[k]) : centre(peak_cells[k]);
    out[k].rays = total[k] * total_weight;
  }
  // The spread of each source's mass: how well its rays actually meet (their pose errors and
  // biases are shared, which the information below, taking them as independent, does not see).
  std::vector<Eigen::Matrix2d> spread(out.size(), Eigen::Matrix2d::Zero());
  for (size_t c = 0; c < owner.size(); ++c) {
    if (owner[c] < 0 || total[owner[c]] <= 0) continue;
    const Eigen::Vector2d d = centre(static_cast<int>(c)) - out[owner[c]].position_m;
    spread[owner[c]] += weight[c] / total[owner[c]] * d * d.transpose();
  }
  // Each ray's responsibility for each source. The rays a source explains (responsibility >= 0.5)
  // give its class votes, times and information: another source's rays that pass near it vote
  // where they belong.
  std::vector<Eigen::Matrix2d> info(out.size(), Eigen::Matrix2d::Zero());
  std::vector<double> nearest(out.size(), INFINITY);
  std::vector<std::vector<double>> heard_from(out.size());  // directions source -> origin
  std::vector<std::pair<int, double>> resp;
  for (size_t i = 0; i < n; ++i) {
    resp.clear();
    for (size_t j = offset[i]; j < offset[i + 1]; ++j) {
      const int c = flat_cell[j];
      const int k = owner[c];
      if (k < 0) continue;
      const double w = weight[c] * flat_a[j] / evidence[i];
      auto it = std::find_if(resp.begin(), resp.end(), [k](const auto& r) { return r.first == k; });
      if (it == resp.end())
        resp.emplace_back(k, w);
      else
        it->second += w;
    }
    const Ray& r = rays_[use[i]];
    const Placed& p = cache_[use[i]].placed;
    for (const auto& [k, w] : resp) {
      Source& s = out[k];
      if (w < 0.5) continue;
      if (r.sound_class > 0 && r.sound_class < 5) s.class_votes[r.sound_class] += w * r.weight;
      s.strong_rays += r.weight;
      heard_from[k].push_back(
          std::atan2(p.origin.y() - s.position_m.y(), p.origin.x() - s.position_m.x()));
      if (s.first_utime == 0 || r.utime < s.first_utime) s.first_utime = r.utime;
      s.last_utime = std::max(s.last_utime, r.utime);
      const Eigen::Vector2d to = s.position_m - p.origin;
      const double d = std::max(to.norm(), options_.min_range_m);
      if (d < nearest[k]) {
        nearest[k] = d;
        s.nearest_origin_m = p.origin;
      }
      const Eigen::Vector2d normal(-to.y() / d, to.x() / d);
      info[k] += w * r.weight * normal * normal.transpose() / (p.sigma * p.sigma * d * d);
    }
  }
  for (size_t k = 0; k < out.size(); ++k) {
    // 1e-6 keeps the information invertible (a source heard from one direction); the cell's
    // own extent, cell^2 / 12, is the finest a position gets.
    info[k] += Eigen::Matrix2d::Identity() * 1e-6;
    Source& s = out[k];
    s.covariance = info[k].inverse() + spread[k] + Eigen::Matrix2d::Identity() * (cell * cell / 12);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s.covariance);
    s.largest_sigma_m = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
    // Parallax: 2 pi less the widest gap between the sorted directions.
    auto& dirs = heard_from[k];
    std::sort(dirs.begin(), dirs.end());
    if (dirs.size() >= 2) {
      double gap = dirs.front() + 2 * M_PI - dirs.back();
      for (size_t j = 1; j < dirs.size(); ++j) gap = std::max(gap, dirs[j] - dirs[j - 1]);
      s.parallax_rad = 2 * M_PI - gap;
    }
  }
  // Sources with too few rays of their own are the mixture's spread, not sources; those
  // outside the site are not reported.
  std::vector<Source> kept;
  for (Source& s : out) {
    const bool inside = !min_m || !max_m ||
                        ((s.position_m.array() >= min_m->array()).all() &&
                         (s.position_m.array() <= max_m->array()).all());
    if (s.strong_rays >= options_.min_rays && inside) kept.push_back(std::move(s));
  }
  out = std::move(kept);
  // A heard direction marks the source it points at best, within its window.
  for (const Ray& h : heard_) {
    Placed p;
    if (!Place(h, node_poses, &p)) continue;
    Source* best = nullptr;
    double best_e = options_.window_sigmas;
    for (Source& s : out) {
      const Eigen::Vector2d to = s.position_m - p.origin;
      const double d = to.norm();
      if (d < options_.min_range_m || d > options_.max_range_m) continue;
      const double e = std::abs(WrapAngle(std::atan2(to.y(), to.x()) - p.bearing)) / p.sigma;
      if (e <= best_e) best_e = e, best = &s;
    }
    if (best) {
      best->heard = true;
      best->called |= h.called;
    }
  }
  return out;
}

namespace {
void WriteRay(common::BinaryWriter* w, const BearingEvidence::Ray& r) {
  w->Pod(r.utime), w->Pod(r.node);
  w->Pod(r.node_from_base.x), w->Pod(r.node_from_base.y), w->Pod(r.node_from_base.yaw);
  w->Pod(r.azimuth_rad), w->Pod(r.sigma_rad), w->Pod<int32_t>(r.sound_class);
  w->Pod<int8_t>(r.heard), w->Pod<int8_t>(r.called);
  w->Pod(r.weight);
}
BearingEvidence::Ray ReadRay(common::BinaryReader* r) {
  BearingEvidence::Ray ray;
  ray.utime = r->Pod<int64_t>(), ray.node = r->Pod<int64_t>();
  ray.node_from_base.x = r->Pod<double>(), ray.node_from_base.y = r->Pod<double>();
  ray.node_from_base.yaw = r->Pod<double>();
  ray.azimuth_rad = r->Pod<double>(), ray.sigma_rad = r->Pod<double>();
  ray.sound_class = r->Pod<int32_t>();
  ray.heard = r->Pod<int8_t>() != 0, ray.called = r->Pod<int8_t>() != 0;
  ray.weight = r->Pod<double>();
  if (!(ray.weight >= 1)) r->Corrupt("a ray's weight below 1");
  return ray;
}
}  // namespace

void BearingEvidence::Save(common::BinaryWriter* w) const {
  for (const auto* list : {&rays_, &heard_}) {
    w->Pod<int64_t>(static_cast<int64_t>(list->size()));
    for (const Ray& r : *list) WriteRay(w, r);
  }
}

void BearingEvidence::Load(common::BinaryReader* r) {
  std::vector<Ray> lists[2];
  for (auto& list : lists) {
    list.resize(static_cast<size_t>(r->Count(10000000)));
    for (Ray& ray : list) ray = ReadRay(r);
  }
  rays_ = std::move(lists[0]);
  heard_ = std::move(lists[1]);
  cache_.clear();
}

}  // namespace sound_map
}  // namespace sarmap
