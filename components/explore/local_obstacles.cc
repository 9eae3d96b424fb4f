#include "explore/local_obstacles.h"

#include <cmath>
#include <limits>

#include "explore/planner.h"

namespace sarmap {
namespace explore {

int64_t LocalObstacles::Key(const Eigen::Vector2d& odom_m) const {
  const int64_t x = static_cast<int64_t>(std::floor(odom_m.x() / cell_m_));
  const int64_t y = static_cast<int64_t>(std::floor(odom_m.y() / cell_m_));
  return static_cast<int64_t>((static_cast<uint64_t>(x) << 32) ^
                              (static_cast<uint64_t>(y) & 0xffffffffu));
}

void LocalObstacles::Add(double stamp_s, const common::Rigid2d& odom_from_base, const Scan& scan) {
  // A clock that steps back: what is kept can no longer be aged.
  if (stamp_s < last_stamp_s_ - 1.0) cells_.clear();
  last_stamp_s_ = stamp_s;
  const common::Rigid2d base_from_odom = odom_from_base.inverse();
  const size_t n = scan.ranges_m.size();
  const bool has_visible = scan.visible_from_m.size() == n;
  const double span_rad = scan.angle_increment_rad * static_cast<double>(n);
  for (auto it = cells_.begin(); it != cells_.end();) {
    const Eigen::Vector2d p = base_from_odom * it->second.odom_m;
    const double range = p.norm();
    bool drop = stamp_s - it->second.seen_s > memory_s_ || range > radius_m_;
    if (!drop && n > 0 && scan.angle_increment_rad > 0 && range > scan.range_min_m) {
      // The beams within a cell of this return, if the scan covers its bearing: all of them must
      // read past it (a return on an edge, placed by odometry a few millimetres off, would
      // otherwise be "seen through" by the beam that grazes the edge).
      const double along = std::atan2(p.y(), p.x()) - scan.angle_min_rad;
      const double window = std::atan2(cell_m_, range);
      if (along - window >= -0.5 * scan.angle_increment_rad && along + window < span_rad) {
        const auto beam = [&](double a) {
          return std::min(
              n - 1, static_cast<size_t>(std::max(0.0, std::round(a / scan.angle_increment_rad))));
        };
        drop = true;
        for (size_t i = beam(along - window); i <= beam(along + window) && drop; ++i) {
          const float r = scan.ranges_m[i];
          const bool reads_beyond = std::isinf(r) ? r > 0 : (r > 0 && r > range + cell_m_);
          const bool in_view = !has_visible || !(scan.visible_from_m[i] > range);
          drop = reads_beyond && in_view;
        }
      }
    }
    it = drop ? cells_.erase(it) : std::next(it);
  }
  for (size_t i = 0; i < n; ++i) {
    const float r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m || r > radius_m_) continue;
    const double a = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const Eigen::Vector2d odom_m =
        odom_from_base * Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
    cells_[Key(odom_m)] = {odom_m, stamp_s};
  }
}

std::vector<Eigen::Vector2d> LocalObstacles::InBase(const common::Rigid2d& odom_from_base) const {
  const common::Rigid2d base_from_odom = odom_from_base.inverse();
  std::vector<Eigen::Vector2d> out;
  out.reserve(cells_.size());
  for (const auto& [key, ret] : cells_) out.push_back(base_from_odom * ret.odom_m);
  return out;
}

double NearestDistance(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& points) {
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& q : points) best = std::min(best, (q - p).squaredNorm());
  return std::sqrt(best);
}

}  // namespace explore
}  // namespace sarmap
