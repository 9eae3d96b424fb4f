#pragma once
// Options of sarmap-slam (config/slam.yaml); the offline runner reads the same file.

#include <string>
#include <vector>

#include "common/options.h"
#include "common/stamp_gate.h"
#include "slam/slam_options.h"

namespace sarmap {
namespace slam {

struct SlamNodeOptions {
  std::string scan_channel = "SCAN";
  std::string odom_channel = "ODOM";
  std::string pose_channel = "POSE";
  std::string map_channel = "MAP";
  std::string anchors_channel = "SLAM_ANCHORS";
  std::string anchor_request_channel = "SLAM_ANCHOR_REQUEST";
  double queue_delay_s = 0.1;        // time-ordering delay of the input queue
  // Scans and odometry LCM holds for the node while it is busy (an optimisation, the covariance,
  // the map): beyond this many per channel the oldest are lost. 30 (LCM's usual) is 1 s of a
  // 30 Hz depth camera; a long mission's graph keeps the node busy for longer than that.
  int input_queue_capacity = 600;
  double map_period_s = 5.0;         // MAP at most this often (message time)
  // Rendering MAP and saving the state cost time in proportion to the graph; each waits until
  // the wall time since its last run is at least its last duration / this fraction (1: no limit).
  double max_busy_fraction = 0.1;
  std::string state_file = "";       // pose-graph file saved periodically and at exit ("" = none)
  double state_save_period_s = 10.0; // message time between periodic saves
  bool resume = false;               // load state_file at start (if it exists) and continue
  std::string load_map = "";         // pose-graph file to localise in (localisation only)
  std::string map_output_prefix = "";  // at exit: PREFIX.pgm + PREFIX.yaml
  std::vector<double> initial_pose = {};  // localisation only: x y yaw (empty: last saved pose)
  double pose_sigma_xy_m = 0.02;     // local matching uncertainty added to POSE covariance
  double pose_sigma_yaw_deg = 0.5;
  // SCAN and ODOM stamped far from their stream's clock are dropped and counted.
  common::StampGateOptions stamp_gate;
  // Anchor requests answered (each a joint covariance over the graph and a SLAM_ANCHORS of up to
  // megabytes): at most this many per client and over all clients per minute; more are refused
  // and counted. Known clients are kept up to max_anchor_clients; a new client beyond that is
  // refused.
  double anchor_replies_per_client_per_min = 12.0;
  double anchor_replies_per_min = 30.0;
  int max_anchor_clients = 16;
  double anchor_client_timeout_s = 60.0;  // a client silent this long frees its place
  int max_anchor_ids_per_request = 256;
  SlamOptions slam;
  template <class V> void Visit(V& v) {
    v("scan_channel", scan_channel, "Input laser scans (laser_scan_t)");
    v("odom_channel", odom_channel, "Input odometry (odometry_t)");
    v("pose_channel", pose_channel, "Output map_from_base (pose_t)");
    v("map_channel", map_channel, "Output occupancy grid (occupancy_grid_t, zstd)");
    v("anchors_channel", anchors_channel, "Output anchors with joint covariance (slam_anchors_t)");
    v("anchor_request_channel", anchor_request_channel, "Input anchor requests (slam_anchor_request_t)");
    v("queue_delay_s", queue_delay_s,
      "Inputs are released in time order this long after arrival (message time)", NonNegative());
    v("input_queue_capacity", input_queue_capacity,
      "Scans / odometry held per channel while the node is busy; beyond it the oldest are lost",
      AtLeast(1));
    v("map_period_s", map_period_s, "Publish MAP at most this often (message time)", Positive());
    v("max_busy_fraction", max_busy_fraction,
      "MAP rendering and state saving each use at most this fraction of the wall time (they slow "
      "with the graph)");
    v("state_file", state_file, "Pose-graph file saved periodically (temp + rename) and at exit");
    v("state_save_period_s", state_save_period_s, "Message time between periodic state saves",
      Positive());
    v("resume", resume, "Load state_file at start if it exists and continue mapping");
    v("load_map", load_map, "Localisation only in this saved pose-graph file");
    v("map_output_prefix", map_output_prefix, "At exit write PREFIX.pgm and PREFIX.yaml (map_server)");
    v("initial_pose", initial_pose, "Localisation only: start pose [x, y, yaw] in the map (empty: last saved pose)");
    v("pose_sigma_xy_m", pose_sigma_xy_m,
      "Local matching standard deviation added to POSE covariance", NonNegative());
    v("pose_sigma_yaw_deg", pose_sigma_yaw_deg,
      "Local matching yaw standard deviation added to POSE covariance", NonNegative());
    v("stamp_gate", stamp_gate,
      "SCAN / ODOM stamped far from their stream's clock are dropped and counted, never adopted");
    v("anchor_replies_per_client_per_min", anchor_replies_per_client_per_min,
      "changed anchor requests answered at once per client per minute; more are deferred (counted) "
      "and the client is served after the next optimisation",
      Positive());
    v("anchor_replies_per_min", anchor_replies_per_min,
      "changed anchor requests answered at once per minute over all clients", Positive());
    v("max_anchor_clients", max_anchor_clients,
      "anchor requests of at most this many clients are kept; requests of further clients are "
      "refused",
      AtLeast(1));
    v("anchor_client_timeout_s", anchor_client_timeout_s,
      "a client that has not repeated its anchor request for this long (wall clock) is forgotten",
      Positive());
    v("max_anchor_ids_per_request", max_anchor_ids_per_request,
      "anchor requests naming more node ids are refused (each id adds 3 rows to the joint "
      "covariance)",
      AtLeast(1));
    v("slam", slam, "SLAM core");
  }
  void Validate(common::Validator& c) const {
    c.That(initial_pose.empty() || initial_pose.size() == 3, "initial_pose",
           "must be empty or [x, y, yaw]");
    c.That(max_busy_fraction > 0 && max_busy_fraction <= 1, "max_busy_fraction",
           "must be in (0, 1]");
  }
};

}  // namespace slam
}  // namespace sarmap
