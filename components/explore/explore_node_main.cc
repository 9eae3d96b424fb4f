// sarmap-explore: exploration (ExploreNode, explore_node.h).
#include "common/node_runner.h"
#include "explore/explore_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<explore::ExploreNode, explore::ExploreNodeOptions>(
      {"sarmap-explore",
       "Drives the robot through an unknown site: frontier exploration on SLAM's map (planner on\n"
       "the inflated grid, pure pursuit, a safety layer on the scan and the map, stuck recovery),\n"
       "people heard but not seen as goals (mode sound_guided), then home; or the Sales 2014\n"
       "reactive behaviour (mode reactive). The operator's TELEOP overrides everything.\n"
       "In: SCAN, MAP, POSE, ODOM, PEOPLE_MAP, TELEOP.  Out: CMD_VEL, EXPLORE_STATUS.",
       "", "config/explore.yaml"},
      argc, argv);
}
