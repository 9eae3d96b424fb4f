#pragma once
// The explorer's messages (generated structs: no LCM runtime needed): ExploreStatus as
// EXPLORE_STATUS, and the people heard on PEOPLE_MAP and the voices on SOUND_MAP as goals.

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "explore/explore.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/sound_map_t.hpp"

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

// sqrt of the largest eigenvalue of the xy block of a row-major 3x3 covariance.
inline double LargestPlanarStd(const double covariance[9]) {
  Eigen::Matrix2d cov;
  cov << covariance[0], covariance[1], covariance[3], covariance[4];
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
                             0.5 * (cov + cov.transpose()), Eigen::EigenvaluesOnly)
                             .eigenvalues()
                             .maxCoeff();
  return std::sqrt(std::max(0.0, largest));
}

// Where everyone on PEOPLE_MAP is, seen or heard.
inline std::vector<Eigen::Vector2d> PeoplePositionsFromMessage(const sarmap::people_map_t& m) {
  std::vector<Eigen::Vector2d> out;
  for (const sarmap::mapped_person_t& p : m.people)
    out.emplace_back(p.position_m[0], p.position_m[1]);
  return out;
}

// The voices on SOUND_MAP: sources with a position (not a bare bearing) classed voice.
inline std::vector<HeardPerson> VoicesFromMessage(const sarmap::sound_map_t& m) {
  std::vector<HeardPerson> voices;
  for (const sarmap::sound_source_t& s : m.sources) {
    if (!s.has_position || s.priority == sarmap::sound_source_t::PRIORITY_NONE) continue;
    bool finite = std::isfinite(s.position_m[0]) && std::isfinite(s.position_m[1]);
    for (int i : {0, 1, 3, 4}) finite &= std::isfinite(s.covariance[i]);
    if (!finite) continue;
    HeardPerson v;
    v.id = s.id;
    v.position_m = Eigen::Vector2d(s.position_m[0], s.position_m[1]);
    v.position_std_m = LargestPlanarStd(s.covariance);
    voices.push_back(v);
  }
  return voices;
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
    h.position_std_m = LargestPlanarStd(p.covariance);
    h.seen = (p.cues & (sarmap::mapped_person_t::CUE_SEEN_RGBD |
                        sarmap::mapped_person_t::CUE_SEEN_DEPTH)) != 0;
    heard.push_back(h);
  }
  return heard;
}

}  // namespace explore
}  // namespace sarmap
