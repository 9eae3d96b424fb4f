// sarmap-slam: 2D graph SLAM (SlamNode, slam_node.h).
#include "common/node_runner.h"
#include "slam/slam_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<slam::SlamNode, slam::SlamNodeOptions>(
      {"sarmap-slam", "2D graph SLAM: SCAN + ODOM in; POSE, MAP, SLAM_ANCHORS out.",
       "Channels (configurable): in SCAN, ODOM, SLAM_ANCHOR_REQUEST; out POSE, MAP, SLAM_ANCHORS.\n"
       "Resume after a crash: --set state_file=run.pg --set resume=true\n"
       "Localisation only:   --set load_map=run.pg",
       "config/slam.yaml"},
      argc, argv);
}
