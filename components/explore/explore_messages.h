#pragma once
// The explorer's messages (generated structs: no LCM runtime needed): ExploreStatus as
// EXPLORE_STATUS, and the people heard on PEOPLE_MAP as goals.

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "explore/explore.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/people_map_t.hpp"

namespace sarmap {
namespace explore {

// `path_stride`: every n-th path point (the last always), so the message stays small.
inline sarmap::explore_status_t ToStatusMessage(const ExploreStatus& s, int64_t utime,
                                                size_t path_stride = 1) {
  sarmap::explore_status_t out{};
  out.header.utime = utime;
  out.header.seq = 0;
  out.header.frame = "map";
  out.state = s.state;
  out.driven_by = s.driven_by;
  out.has_goal = s.goal_m.has_value();
  out.goal_kind = s.goal_kind;
  out.goal_m[0] = s.goal_m ? s.goal_m->x() : 0.0;
  out.goal_m[1] = s.goal_m ? s.goal_m->y() : 0.0;
  const size_t stride = path_stride > 0 ? path_stride : 1;
  for (size_t i = 0; i < s.path.size(); i += stride) {
    out.path_x_m.push_back(static_cast<float>(s.path[i].x()));
    out.path_y_m.push_back(static_cast<float>(s.path[i].y()));
  }
  if (!s.path.empty() && (s.path.size() - 1) % stride != 0) {
    out.path_x_m.push_back(static_cast<float>(s.path.back().x()));
    out.path_y_m.push_back(static_cast<float>(s.path.back().y()));
  }
  out.num_path = static_cast<int32_t>(out.path_x_m.size());
  out.frontiers = s.frontiers;
  out.blacklisted = s.blacklisted;
  out.recoveries = s.recoveries;
  out.stuck_s = s.stuck_s;
  out.elapsed_s = s.elapsed_s;
  return out;
}

// The people heard on PEOPLE_MAP: position, the largest planar standard deviation, and
// whether they were also seen.
inline std::vector<HeardPerson> HeardPeopleFromMessage(const sarmap::people_map_t& m) {
  std::vector<HeardPerson> heard;
  for (const sarmap::mapped_person_t& p : m.people) {
    if (!(p.cues & sarmap::mapped_person_t::CUE_HEARD)) continue;
    HeardPerson h;
    h.id = p.id;
    h.position_m = Eigen::Vector2d(p.position_m[0], p.position_m[1]);
    Eigen::Matrix2d cov;
    cov << p.covariance[0], p.covariance[1], p.covariance[3], p.covariance[4];
    const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
                               0.5 * (cov + cov.transpose()), Eigen::EigenvaluesOnly)
                               .eigenvalues()
                               .maxCoeff();
    h.position_std_m = std::sqrt(std::max(0.0, largest));
    h.seen = (p.cues & (sarmap::mapped_person_t::CUE_SEEN_RGBD |
                        sarmap::mapped_person_t::CUE_SEEN_DEPTH)) != 0;
    heard.push_back(h);
  }
  return heard;
}

}  // namespace explore
}  // namespace sarmap
