#pragma once
// What the operator's page shows of each message (adapters only: the viewer's core has no
// message types).

#include <string>
#include <vector>

#include "common/transform.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/node_status_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pm_info_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "viewer/viewer_state.h"

namespace sarmap {
namespace viewer {

std::vector<PersonView> PeopleViews(const people_map_t& m);
std::vector<SourceView> SourceViews(const sound_map_t& m);
std::vector<ProcessView> ProcessViews(const pm_info_t& m);
NodeView NodeViewOf(const node_status_t& m, double now_s);
MissionView MissionViewOf(const explore_status_t& m);
// The scan's returns within its range limits, in the map frame.
std::vector<Eigen::Vector2d> ScanPointsInMap(const laser_scan_t& m,
                                             const common::Rigid2d& map_from_base);

}  // namespace viewer
}  // namespace sarmap
