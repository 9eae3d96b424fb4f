// sarmap-explore: SCAN, MAP, POSE and TELEOP in; CMD_VEL out, one command per scan.
#include <cstdio>

#include "common/node_main.h"
#include "common/image_messages.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/robot_config.h"
#include "explore/explore.h"

namespace {

struct NodeOptions {
  std::string scan_channel = "SCAN";
  std::string map_channel = "MAP";
  std::string pose_channel = "POSE";
  std::string teleop_channel = "TELEOP";
  std::string command_channel = "CMD_VEL";
  sarmap::explore::ExploreOptions explore;
  template <class V>
  void Visit(V& v) {
    v("scan_channel", scan_channel, "laser scan (the safety layer)");
    v("map_channel", map_channel, "occupancy grid for frontier exploration");
    v("pose_channel", pose_channel, "robot pose in the map");
    v("teleop_channel", teleop_channel, "operator override");
    v("command_channel", command_channel, "velocity commands out");
    v("explore", explore, "exploration");
  }
};

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-explore", [&] {
    using namespace sarmap;
    common::ArgParser parser(
        "sarmap-explore",
        "Drives the robot: the Sales 2014 reactive behaviour on the scan, frontier exploration on\n"
        "the map with the reactive behaviour as safety layer, and the operator's TELEOP override\n"
        "(with an emergency stop that holds until released).\n"
        "In: SCAN, MAP, POSE, TELEOP.  Out: CMD_VEL.");
    common::NodeArgs args;
    const auto parsed = common::ParseNodeOptions<NodeOptions>(&parser, &args, argc, argv, "config/explore.yaml");
    if (!parsed) return 0;
    const NodeOptions& options = *parsed;
    common::Node node("sarmap-explore", args.lcm_url);
    explore::ExploreController controller(options.explore);
    auto publisher = node.Advertise<velocity_command_t>(options.command_channel);
    std::string last_source;

    node.Subscribe<teleop_t>(options.teleop_channel, [&](const teleop_t& m, const common::ReceiveInfo&) {
      explore::TeleopCommand t;
      t.utime = m.header.utime;
      t.override_active = m.override_active;
      t.emergency_stop = m.emergency_stop;
      t.linear_mps = m.linear_mps;
      t.angular_radps = m.angular_radps;
      controller.OnTeleop(t);
    });
    node.Subscribe<pose_t>(options.pose_channel, [&](const pose_t& m, const common::ReceiveInfo&) {
      controller.OnPose(common::ToRigid3d(m.position_m, m.orientation).ToRigid2d());
    }, 1);
    node.Subscribe<occupancy_grid_t>(options.map_channel, [&](const occupancy_grid_t& m, const common::ReceiveInfo&) {
      if (std::abs(m.origin_yaw_rad) > 1e-6) {
        SARMAP_LOG(WARN) << "rotated grids are not supported for exploration; map ignored";
        return;
      }
      explore::Grid grid;
      grid.width = m.width;
      grid.height = m.height;
      grid.resolution_m = m.resolution_m;
      grid.origin_x_m = m.origin_x_m;
      grid.origin_y_m = m.origin_y_m;
      std::string error;
      if (!common::DecodeOccupancyGrid(m, &grid.cells, &error)) {
        SARMAP_LOG(WARN) << "bad MAP: " << error;
        return;
      }
      controller.OnMap(std::move(grid));
    }, 1);
    node.Subscribe<laser_scan_t>(options.scan_channel, [&](const laser_scan_t& m, const common::ReceiveInfo&) {
      explore::Scan scan;
      scan.angle_min_rad = m.angle_min_rad;
      scan.angle_increment_rad = m.angle_increment_rad;
      scan.range_min_m = m.range_min_m;
      scan.range_max_m = m.range_max_m;
      scan.ranges_m = m.ranges_m;
      const explore::Velocity v = controller.OnScan(m.header.utime, scan);
      velocity_command_t cmd;
      cmd.header.utime = m.header.utime;
      cmd.header.frame = "base";
      cmd.linear_mps = v.linear_mps;
      cmd.angular_radps = v.angular_radps;
      cmd.source = v.source;
      publisher.Publish(&cmd);
      if (v.source != last_source) {
        SARMAP_LOG(INFO) << "now driven by " << v.source;
        last_source = v.source;
        node.SetStatusMessage("driven by " + v.source + (controller.finished() ? " (exploration finished)" : ""));
      }
    }, 1);
    return node.Run();
  });
}
