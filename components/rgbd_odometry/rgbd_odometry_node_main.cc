// sarmap-rgbd-odometry: RGB-D odometry of a hand-held rig (RgbdOdometryNode,
// rgbd_odometry_node.h).
#include "common/node_runner.h"
#include "rgbd_odometry/rgbd_odometry_node.h"

int main(int argc, char** argv) {
  using namespace sarmap;
  return common::RunNode<rgbd_odometry::RgbdOdometryNode, rgbd_odometry::RgbdOdometryNodeOptions>(
      {"sarmap-rgbd-odometry",
       "6-DoF odometry of a hand-held RGB-D rig (OpenCV rgbd module): DEPTH (+ RGB for the\n"
       "rgbd and rgbd_icp methods, paired by utime) in, the rig pose out (pose_t on RIG_POSE,\n"
       "frame odom -> rig, body convention x forward, y left, z up; odom = the rig at the\n"
       "first frame).",
       "Examples:\n"
       "  sarmap-depth & sarmap-rgbd-odometry              # OpenNI2 camera -> RIG_POSE\n"
       "  sarmap-rgbd-odometry --set odometry.method=icp   # depth only (dark rooms)\n"
       "  sarmap-rgbd-odometry --set odometry.image_scale=1 --print-config",
       "config/rgbd_odometry.yaml"},
      argc, argv);
}
