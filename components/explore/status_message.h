#pragma once
// ExploreStatus as the EXPLORE_STATUS message (a generated struct: no LCM runtime needed).

#include <cstddef>
#include <cstdint>

#include "explore/explore.h"
#include "sarmap/explore_status_t.hpp"

namespace sarmap {
namespace explore {

// `path_stride`: every n-th path point (the last always), so the message stays small.
inline sarmap::explore_status_t ToStatusMessage(const ExploreStatus& s, int64_t utime,
                                                size_t path_stride = 1) {
  sarmap::explore_status_t out;
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

}  // namespace explore
}  // namespace sarmap
