#pragma once
// Options of sarmap-explore (config/explore.yaml): channels, and the controller's options.
// The in-process mission runner reads the same file through it.

#include <string>

#include "common/options.h"
#include "common/stamp_gate.h"
#include "explore/explore.h"

namespace sarmap {
namespace explore {

struct ExploreNodeOptions {
  std::string scan_channel = "SCAN";
  std::string map_channel = "MAP";
  std::string pose_channel = "POSE";
  std::string odometry_channel = "ODOM";
  std::string people_channel = "PEOPLE_MAP";
  std::string sound_map_channel = "SOUND_MAP";
  std::string teleop_channel = "TELEOP";
  std::string command_channel = "CMD_VEL";
  std::string status_channel = "EXPLORE_STATUS";
  double status_period_s = 0.5;
  // sarmap-depth's SCAN carries each return's visible-from range in its intensities; a laser's
  // intensities are reflectance and must not be read so.
  bool scan_intensities_are_visible_from = true;
  // Signed commands (common/command_auth.h): CMD_VEL is signed with this key and TELEOP is
  // obeyed only when signed with it; empty: unsigned (any host on the bus can command).
  std::string command_key_file;
  // SCAN is gated on its own clock: a forged scan stamped far ahead would otherwise become a
  // command stamped far ahead (CMD_VEL carries the scan's stamp).
  common::StampGateOptions stamp_gate;
  ExploreOptions explore;
  template <class V>
  void Visit(V& v) {
    v("scan_channel", scan_channel,
      "laser scan (safety layer, and the explorer's picture between maps)");
    v("map_channel", map_channel, "occupancy grid from SLAM");
    v("pose_channel", pose_channel, "robot pose in the map");
    v("odometry_channel", odometry_channel,
      "wheel (or visual) odometry: the frame of the safety layer's memory of recent returns; "
      "empty or silent: SLAM's pose is used");
    v("people_channel", people_channel,
      "people map: people heard but not seen become goals (mode sound_guided)");
    v("sound_map_channel", sound_map_channel,
      "sound map: voices nobody on the people map explains become goals (mode sound_guided, "
      "explore.sound.voices); empty: none");
    v("teleop_channel", teleop_channel, "operator override");
    v("command_channel", command_channel, "velocity commands out");
    v("status_channel", status_channel, "mission state, goal and path out");
    v("status_period_s", status_period_s, "EXPLORE_STATUS at most this often", Positive());
    v("scan_intensities_are_visible_from", scan_intensities_are_visible_from,
      "SCAN's intensities are each return's visible-from range, as sarmap-depth publishes them "
      "(a depth camera looks over low objects close by); false for a laser's reflectance");
    v("command_key_file", command_key_file,
      "key (>= 16 random bytes, mode 600) that signs CMD_VEL and must sign TELEOP; empty: "
      "unsigned");
    v("stamp_gate", stamp_gate,
      "SCAN stamped far from its stream's clock is dropped and counted "
      "(components/common/README.md)");
    v("explore", explore, "exploration");
  }
};

}  // namespace explore
}  // namespace sarmap
