#pragma once
// ExploreNode: the LCM adapter of exploration. SCAN, MAP, POSE, ODOM, PEOPLE_MAP and TELEOP in;
// CMD_VEL (one per scan, signed with the command key when one is configured) and
// EXPLORE_STATUS out, around explore::ExploreController. TELEOP is obeyed only when it passes
// the command gate (signed with the key, newer than the last one); SCAN is gated on its own
// clock, as a command carries the scan's stamp.

#include <string>

#include "common/command_auth.h"
#include "common/node.h"
#include "common/stamp_gate.h"
#include "explore/explore.h"
#include "explore/explore_node_options.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/laser_scan_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/odometry_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/teleop_t.hpp"
#include "sarmap/velocity_command_t.hpp"

namespace sarmap {
namespace explore {

class ExploreNode {
 public:
  // Throws std::runtime_error for a command key file that cannot be used.
  ExploreNode(const ExploreNodeOptions& options, common::Node* node);

  const ExploreController& controller() const { return controller_; }

 private:
  void OnTeleop(const teleop_t& m, const common::ReceiveInfo& info);
  void OnPose(const pose_t& m);
  void OnOdometry(const odometry_t& m, const common::ReceiveInfo& info);
  void OnMap(const occupancy_grid_t& m);
  void OnPeople(const people_map_t& m);
  void OnSoundMap(const sound_map_t& m);
  void OnScan(const laser_scan_t& m, const common::ReceiveInfo& info);
  void PublishStatus(int64_t utime, const ExploreStatus& s);

  ExploreNodeOptions options_;
  common::Node* node_;
  ExploreController controller_;
  common::Node::Publisher<velocity_command_t> command_pub_;
  common::Node::Publisher<explore_status_t> status_pub_;
  std::string last_state_;
  double last_status_s_ = -1e9;
  common::AuthKey command_key_;
  common::CommandGate teleop_gate_;
  common::StampGates scan_gate_{options_.stamp_gate};
};

}  // namespace explore
}  // namespace sarmap
