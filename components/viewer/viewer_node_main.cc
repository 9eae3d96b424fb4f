// sarmap-viewer: the operator's live web page (ViewerNode, viewer_node.h).
#include "common/node_runner.h"
#include "viewer/viewer_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<viewer::ViewerNode, viewer::ViewerNodeOptions>(
      {"sarmap-viewer",
       "The operator's live web page: map, robot pose and trail, scan, people (seen, heard with\n"
       "their uncertainty, both), sound sources with 3-sigma ellipses, a camera thumbnail and\n"
       "process status from the launcher. Read-only.\n"
       "In: MAP, POSE, SCAN, PEOPLE_MAP, SOUND_MAP, RGB, EXPLORE_STATUS, PM_INFO, NODE_STATUS.  "
       "Out: HTTP.",
       "", "config/viewer.yaml"},
      argc, argv);
}
