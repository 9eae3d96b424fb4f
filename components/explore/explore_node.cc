#include "explore/explore_node.h"

#include <cmath>

#include "common/image_messages.h"
#include "common/logging.h"
#include "common/message_conversions.h"
#include "explore/explore_messages.h"

namespace sarmap {
namespace explore {

ExploreNode::ExploreNode(const ExploreNodeOptions& options, common::Node* node)
    : options_(options),
      node_(node),
      controller_(options.explore),
      command_pub_(node->Advertise<velocity_command_t>(options.command_channel)),
      status_pub_(node->Advertise<explore_status_t>(options.status_channel)) {
  if (!options.command_key_file.empty()) {
    command_key_ = common::LoadAuthKeyFile(options.command_key_file);
    teleop_gate_ = common::CommandGate(command_key_);
  } else {
    SARMAP_LOG(WARN)
        << "no command_key_file: CMD_VEL goes out unsigned and any TELEOP on the bus is obeyed";
  }
  node->Subscribe<teleop_t>(
      options.teleop_channel,
      [this](const teleop_t& m, const common::ReceiveInfo& info) { OnTeleop(m, info); });
  // Poses and odometry are cheap to take and each one counts (the trail, the odometry history),
  // so they queue like any input; MAP and SCAN are latest-only: a newer one replaces a stale one,
  // whose handling (the grid, a control step) would only delay it.
  node->Subscribe<pose_t>(options.pose_channel,
                          [this](const pose_t& m, const common::ReceiveInfo&) { OnPose(m); });
  if (!options.odometry_channel.empty()) {
    node->Subscribe<odometry_t>(
        options.odometry_channel,
        [this](const odometry_t& m, const common::ReceiveInfo& info) { OnOdometry(m, info); });
  }
  node->Subscribe<occupancy_grid_t>(
      options.map_channel,
      [this](const occupancy_grid_t& m, const common::ReceiveInfo&) { OnMap(m); }, 1);
  node->Subscribe<people_map_t>(
      options.people_channel,
      [this](const people_map_t& m, const common::ReceiveInfo&) { OnPeople(m); }, 5);
  if (!options.sound_map_channel.empty()) {
    node->Subscribe<sound_map_t>(
        options.sound_map_channel,
        [this](const sound_map_t& m, const common::ReceiveInfo&) { OnSoundMap(m); }, 5);
  }
  node->Subscribe<laser_scan_t>(
      options.scan_channel,
      [this](const laser_scan_t& m, const common::ReceiveInfo& info) { OnScan(m, info); }, 1);
}

void ExploreNode::OnTeleop(const teleop_t& m, const common::ReceiveInfo& info) {
  std::string why;
  if (!teleop_gate_.Accept(m, &why)) {
    node_->Reject(info.channel, "TELEOP " + why);
    return;
  }
  TeleopCommand t;
  // The dead man runs on this process's clock: a sender's stamp ahead of ours must not
  // keep an override alive.
  t.receive_time_s = info.receive_time_s;
  t.override_active = m.override_active;
  t.emergency_stop = m.emergency_stop;
  t.linear_mps = m.linear_mps;
  t.angular_radps = m.angular_radps;
  controller_.OnTeleop(t);
}

void ExploreNode::OnPose(const pose_t& m) {
  controller_.OnPose(common::ToRigid3d(m.position_m, m.orientation).ToRigid2d(),
                     common::UtimeToSeconds(m.header.utime));
}

void ExploreNode::OnOdometry(const odometry_t& m, const common::ReceiveInfo& info) {
  const common::Rigid2d odom_from_base = common::ToRigid3d(m.position_m, m.orientation).ToRigid2d();
  if (!odom_from_base.translation().allFinite() || !std::isfinite(odom_from_base.yaw_rad())) {
    node_->Reject(info.channel, "odometry with a non-finite pose");
    return;
  }
  controller_.OnOdometry(odom_from_base, common::UtimeToSeconds(m.header.utime));
}

void ExploreNode::OnMap(const occupancy_grid_t& m) {
  if (std::abs(m.origin_yaw_rad) > 1e-6) {
    SARMAP_LOG(WARN) << "rotated grids are not supported for exploration; map ignored";
    return;
  }
  Grid grid;
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
  controller_.OnMap(grid);
}

void ExploreNode::OnPeople(const people_map_t& m) {
  controller_.OnPeopleMap(HeardPeopleFromMessage(m), PeoplePositionsFromMessage(m));
}

void ExploreNode::OnSoundMap(const sound_map_t& m) { controller_.OnVoices(VoicesFromMessage(m)); }

void ExploreNode::OnScan(const laser_scan_t& m, const common::ReceiveInfo& info) {
  if (!scan_gate_.Accept(0, m.header.utime, info.receive_time_s)) {
    node_->Reject(info.channel,
                  "stamp " + std::to_string(m.header.utime) + " far from the stream's clock");
    return;
  }
  Scan scan;
  scan.stamp_s = common::UtimeToSeconds(m.header.utime);
  scan.angle_min_rad = m.angle_min_rad;
  scan.angle_increment_rad = m.angle_increment_rad;
  scan.range_min_m = m.range_min_m;
  scan.range_max_m = m.range_max_m;
  scan.ranges_m = m.ranges_m;
  if (options_.scan_intensities_are_visible_from && m.num_intensities == m.num_ranges) {
    scan.visible_from_m = m.intensities;
  }
  const Velocity v = controller_.OnScan(info.receive_time_s, scan);
  velocity_command_t cmd{};
  cmd.header.utime = m.header.utime;
  cmd.header.frame = "base";
  cmd.linear_mps = v.linear_mps;
  cmd.angular_radps = v.angular_radps;
  cmd.source = v.source;
  if (command_key_.empty()) {
    command_pub_.Publish(&cmd);
  } else {
    command_pub_.Publish(&cmd,
                         [this](velocity_command_t* c) { common::SignMessage(command_key_, c); });
  }
  const ExploreStatus& s = controller_.status();
  if (s.state != last_state_) {
    SARMAP_LOG(INFO) << "mission state " << s.state
                     << (s.goal_kind.empty() ? "" : ", goal " + s.goal_kind);
    last_state_ = s.state;
    node_->SetStatusMessage(s.state + ", driven by " + v.source);
  }
  if (info.receive_time_s - last_status_s_ >= options_.status_period_s) {
    last_status_s_ = info.receive_time_s;
    PublishStatus(m.header.utime, s);
  }
}

void ExploreNode::PublishStatus(int64_t utime, const ExploreStatus& s) {
  // Every 4th path point (20 cm) is enough to draw it.
  explore_status_t out = ToStatusMessage(s, utime, 4);
  status_pub_.Publish(&out);  // sets the sequence number
}

}  // namespace explore
}  // namespace sarmap
