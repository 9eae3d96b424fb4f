#pragma once
// Options of the SLAM core (config/slam.yaml, section "slam" of the node's options).

#include <cmath>
#include <string>

#include "common/options.h"

namespace sarmap {
namespace slam {

using common::Validator;

struct ScanOptions {
  double min_range_m = 0.1;
  double max_range_m = 30.0;              // returns farther are used as free-space rays only
  double missing_data_ray_length_m = 5.0; // free-space ray for "no return" beams
  double voxel_size_m = 0.025;
  double adaptive_max_length_m = 0.5;     // points used for local matching
  int adaptive_min_points = 200;
  double loop_adaptive_max_length_m = 0.9;  // points kept for loop closure
  int loop_adaptive_min_points = 100;
  // MAP only: rays clear cells from this range on. A depth camera at height h whose lowest ray
  // points a below the horizon sees an object of height z from (h - z) / tan(a) on; closer in,
  // its scan's rays pass over low objects, and clearing there would erase them from MAP.
  double map_free_from_m = 0.0;
  // MAP as published (Slam::DrawMap): "nodes" draws it from every live node's scan (cost grows
  // with the live nodes; honours map_free_from_m), keeping the drawing between calls and
  // drawing it again only when an optimisation has moved some drawn return by more than
  // map_redraw_shift_cells: below half a cell, a return stays in its cell or moves to a
  // neighbour, which is the grid's own rounding. "submaps" composes it from the live submaps'
  // grids at their optimised poses (cost grows with the mapped area; Slam::ComposeMap).
  std::string map_source = "nodes";
  double map_redraw_shift_cells = 0.5;
  // Pose of the laser on the robot (base_from_laser).
  double laser_x_m = 0, laser_y_m = 0, laser_yaw_rad = 0;
  template <class V> void Visit(V& v) {
    v("min_range_m", min_range_m, "Shorter ranges are ignored", NonNegative());
    v("max_range_m", max_range_m, "Longer ranges only clear free space (up to missing_data_ray_length_m)");
    v("missing_data_ray_length_m", missing_data_ray_length_m,
      "Free-space ray length for no-return beams", NonNegative());
    v("voxel_size_m", voxel_size_m, "Voxel filter size applied to each scan", Positive());
    v("adaptive_max_length_m", adaptive_max_length_m,
      "Adaptive voxel filter: largest voxel for local matching", Positive());
    v("adaptive_min_points", adaptive_min_points,
      "Adaptive voxel filter: keep at least this many points", Positive());
    v("loop_adaptive_max_length_m", loop_adaptive_max_length_m,
      "Adaptive voxel filter for loop-closure points", Positive());
    v("loop_adaptive_min_points", loop_adaptive_min_points, "Minimum loop-closure points per node",
      Positive());
    v("map_free_from_m", map_free_from_m,
      "MAP: rays clear cells only from this range on (a depth camera's rays pass over low objects "
      "closer in); 0: from the sensor",
      NonNegative());
    v("map_source", map_source,
      "MAP as published: drawn from every live node's scan (nodes), or composed from the live "
      "submaps' grids (submaps; not with map_free_from_m)",
      OneOf({"submaps", "nodes"}));
    v("map_redraw_shift_cells", map_redraw_shift_cells,
      "MAP from nodes: drawn again from every node when an optimisation moves a drawn return by "
      "more than this (cells); otherwise only new nodes are drawn",
      NonNegative());
    v("laser_x_m", laser_x_m, "base_from_laser x, for scans that carry no laser pose of their own");
    v("laser_y_m", laser_y_m, "base_from_laser y, for scans that carry no laser pose of their own");
    v("laser_yaw_rad", laser_yaw_rad,
      "base_from_laser yaw, for scans that carry no laser pose of their own");
  }
  void Validate(Validator& c) const {
    c.That(max_range_m > min_range_m, "max_range_m", "must be > min_range_m");
    c.That(map_free_from_m == 0 || map_source == "nodes", "map_free_from_m",
           "needs map_source: nodes (the submaps' grids clear cells from the sensor on)");
  }
};

struct LocalOptions {
  double resolution_m = 0.05;
  int scans_per_submap = 90;
  double hit_probability = 0.55;
  double miss_probability = 0.49;
  bool use_correlative_search = true;
  double correlative_linear_window_m = 0.1;
  double correlative_angular_window_deg = 15.0;
  double correlative_translation_cost = 2.0;
  double correlative_rotation_cost = 0.1;
  bool ceres_rotation_prior_from_prediction = false;
  // Odometry that does not change between scans: a stale stream (CARMEN logs freeze it while the
  // robot moves, false) or a robot standing still (a live driver, true).
  bool unchanged_odometry_means_stopped = false;
  // A scan newer than the last odometry reading, in a turn at least min_turn_radps: extrapolate
  // the last odometry step up to this far ahead (s) instead of holding the last reading
  // (0: always hold, as for CARMEN logs).
  double odometry_extrapolation_s = 0;
  double odometry_extrapolation_min_turn_radps = 0.1;
  // Local matching uses only the scan's points where the matching submap knows the space
  // around them (MatchablePoints): what the scan sees first lands on cells that cost as much as
  // free space and pulls the match back towards the known map.
  bool match_known_space_only = false;
  double wide_search_below_score = 0.5;
  double wide_linear_window_m = 0.3;
  double wide_angular_window_deg = 45.0;
  double ceres_occupied_weight = 1.0;
  double ceres_translation_weight = 10.0;
  double ceres_rotation_weight = 40.0;
  int ceres_max_iterations = 20;
  // Rotation prior adapted to what the scan tells about heading (I = number of points x
  // RotationInformation at the correlative result): the weight is ceres_rotation_weight while I <= info_low and
  // ceres_rotation_weight_informative once I >= info_high, log-linear in between.
  // 0 (the default) keeps ceres_rotation_weight for every scan.
  double ceres_rotation_weight_informative = 0;
  double rotation_information_low = 3e3;
  double rotation_information_high = 1e4;
  // Motion filter: a scan becomes a graph node (and is inserted) only when the robot moved.
  double node_max_time_s = 5.0;
  double node_max_distance_m = 0.2;
  double node_max_angle_deg = 1.0;
  template <class V> void Visit(V& v) {
    v("resolution_m", resolution_m, "Submap cell size", Positive());
    v("scans_per_submap", scans_per_submap,
      "Scans inserted before a new submap starts (each submap gets 2x)", AtLeast(2));
    v("hit_probability", hit_probability, "Occupancy update for a return", InRange(0.5001, 0.99));
    v("miss_probability", miss_probability, "Occupancy update for a cell a ray passes",
      InRange(0.01, 0.4999));
    v("use_correlative_search", use_correlative_search, "Correlative search before the Ceres refinement");
    v("correlative_linear_window_m", correlative_linear_window_m,
      "Correlative search half-window (m)", NonNegative());
    v("correlative_angular_window_deg", correlative_angular_window_deg,
      "Correlative search half-window (deg)", NonNegative());
    v("correlative_translation_cost", correlative_translation_cost, "Penalty weight on translation from prediction");
    v("correlative_rotation_cost", correlative_rotation_cost, "Penalty weight on rotation from prediction");
    v("ceres_rotation_prior_from_prediction", ceres_rotation_prior_from_prediction,
      "Scan matcher: the rotation prior is the prediction (for robots with good odometry in scenes "
      "that barely constrain rotation, e.g. a glass corridor; wrong for Intel/ACES/MIT's odometry)");
    v("unchanged_odometry_means_stopped", unchanged_odometry_means_stopped,
      "Odometry that does not change means the robot stands still: the scan is matched against "
      "the pose where it stopped, so a featureless view cannot creep (false: the stream is stale "
      "and a constant-velocity model predicts, for logs that freeze odometry while moving)");
    v("odometry_extrapolation_s", odometry_extrapolation_s,
      "A scan up to this much newer than the last odometry reading is predicted by extrapolating "
      "the last odometry step, in turns (0: the last reading is held)",
      InRange(0.0, 0.5));
    v("odometry_extrapolation_min_turn_radps", odometry_extrapolation_min_turn_radps,
      "Odometry extrapolation only while the odometry turns at least this fast (rad/s)",
      NonNegative());
    v("match_known_space_only", match_known_space_only,
      "Local matching leaves out the scan's points on cells the matching submap has not observed, "
      "or observed only as a sliver (no known cell on either side along some direction): the part "
      "of a scan seen for the first time otherwise pulls the match back towards the known map, "
      "and a narrow scan shrinks a corridor by several per cent");
    v("wide_search_below_score", wide_search_below_score, "Search the wide window when the match scores below this");
    v("wide_linear_window_m", wide_linear_window_m, "Wide correlative search half-window (m), when the match hits the window edge or scores low");
    v("wide_angular_window_deg", wide_angular_window_deg, "Wide correlative search half-window (deg)");
    v("ceres_occupied_weight", ceres_occupied_weight, "Scan matcher: weight of the map term");
    v("ceres_translation_weight", ceres_translation_weight, "Scan matcher: weight of staying at the prior translation");
    v("ceres_rotation_weight", ceres_rotation_weight, "Scan matcher: weight of staying at the prior rotation");
    v("ceres_max_iterations", ceres_max_iterations, "Scan matcher iterations", Positive());
    v("ceres_rotation_weight_informative", ceres_rotation_weight_informative,
      "Scan matcher: rotation prior weight for a scan whose heading information (1/rad^2) is at "
      "least rotation_information_high (0: off, ceres_rotation_weight always)",
      NonNegative());
    v("rotation_information_low", rotation_information_low,
      "Scan matcher: heading information at or below which ceres_rotation_weight applies");
    v("rotation_information_high", rotation_information_high,
      "Scan matcher: heading information at or above which ceres_rotation_weight_informative applies");
    v("node_max_time_s", node_max_time_s, "Motion filter: new node after this time");
    v("node_max_distance_m", node_max_distance_m, "Motion filter: new node after this distance");
    v("node_max_angle_deg", node_max_angle_deg, "Motion filter: new node after this rotation");
  }
  void Validate(Validator& c) const {
    c.That(rotation_information_low > 0 && rotation_information_high > rotation_information_low,
           "rotation_information_high", "must be > rotation_information_low > 0");
  }
};

struct LoopClosureOptions {
  double sampling_ratio = 0.3;        // fraction of (node, submap) pairs tried
  double max_constraint_distance_m = 15.0;
  double min_score = 0.65;            // verification: mean matched probability
  double linear_window_m = 5.0;
  double angular_window_deg = 20.0;
  int branch_and_bound_depth = 7;
  double ceres_occupied_weight = 20.0;
  double ceres_translation_weight = 10.0;
  double ceres_rotation_weight = 1.0;
  double translation_weight = 1.1e4;
  double rotation_weight = 1e5;
  int max_cached_precomputations = 8;
  int max_submaps_per_node = 8;       // nearest finished submaps searched for a new node
  int max_old_nodes_per_submap = 60;  // older nodes searched against a newly finished submap
  // A loop closure's translation weight follows the match's own information per direction
  // (Constraint::translation_shape): translation_weight along the direction the match tells
  // best, less along one it cannot tell (a scan of one wall slides along it). Off: one weight
  // for every direction.
  bool weight_by_match_information = false;
  // Consistency gate (loop_consistency.h): a closure is kept only when its squared Mahalanobis
  // distance to the graph's current estimate of the same relative pose is at most
  // consistency_max_chi2, with a covariance of local SLAM's drift along the path between the
  // node and the submap's node nearest the match (random walk per sqrt(m) driven and per
  // sqrt(rad) turned), plus two scan-to-submap matches' noise (the closure's and the
  // submap node's own).
  bool consistency_gate = false;
  // A match whose best pose lies on the search window's outermost row or column of
  // translations, or at its outermost angle, is no verified maximum: the score may still rise
  // outside the window, and in a corridor or a row of alike rooms it is where a sliding match
  // comes to rest.
  bool reject_window_edge = false;
  double consistency_drift_m_per_sqrt_m = 0.1;
  double consistency_drift_deg_per_sqrt_rad = 1.15;
  double consistency_drift_deg_per_sqrt_m = 0.5;
  double consistency_match_sigma_m = 0.05;
  double consistency_match_sigma_deg = 1.0;
  double consistency_max_chi2 = 16.27;  // chi-square, 3 degrees of freedom, 99.9 %
  template <class V> void Visit(V& v) {
    v("sampling_ratio", sampling_ratio, "Fraction of (node, finished submap) pairs searched",
      InRange(0, 1));
    v("max_constraint_distance_m", max_constraint_distance_m, "Only search submaps this close to the node");
    v("min_score", min_score,
      "Accept a loop closure when its mean matched probability is at least this", InRange(0, 1));
    v("linear_window_m", linear_window_m, "Branch-and-bound half-window (m)");
    v("angular_window_deg", angular_window_deg, "Branch-and-bound half-window (deg)");
    v("branch_and_bound_depth", branch_and_bound_depth, "Levels of the precomputation stack",
      InRange(1, 12));
    v("ceres_occupied_weight", ceres_occupied_weight, "Refinement: map term weight");
    v("ceres_translation_weight", ceres_translation_weight, "Refinement: translation prior weight");
    v("ceres_rotation_weight", ceres_rotation_weight, "Refinement: rotation prior weight");
    v("translation_weight", translation_weight, "Pose graph weight of loop closures (translation)");
    v("rotation_weight", rotation_weight, "Pose graph weight of loop closures (rotation)");
    v("max_cached_precomputations", max_cached_precomputations,
      "Submap precomputation stacks kept in memory (least recently used; a stack is rebuilt in "
      "milliseconds)",
      AtLeast(1));
    v("max_submaps_per_node", max_submaps_per_node,
      "A new node is searched against at most this many nearest finished submaps", AtLeast(0));
    v("max_old_nodes_per_submap", max_old_nodes_per_submap,
      "A newly finished submap is searched for at most this many older nodes", AtLeast(0));
    v("weight_by_match_information", weight_by_match_information,
      "Loop closure translation weight per direction follows the match's information (a match along a wall pulls across it, not along it)");
    v("consistency_gate", consistency_gate,
      "Reject a loop closure inconsistent with the graph's current estimate, given local SLAM's drift along the path between its ends");
    v("reject_window_edge", reject_window_edge,
      "Reject a loop closure whose best pose lies on the branch-and-bound window's boundary (not a verified maximum)");
    v("consistency_drift_m_per_sqrt_m", consistency_drift_m_per_sqrt_m,
      "Consistency gate: local SLAM's position drift, std per sqrt(metre driven) (random walk)",
      NonNegative());
    v("consistency_drift_deg_per_sqrt_rad", consistency_drift_deg_per_sqrt_rad,
      "Consistency gate: heading drift, std (deg) per sqrt(radian turned)", NonNegative());
    v("consistency_drift_deg_per_sqrt_m", consistency_drift_deg_per_sqrt_m,
      "Consistency gate: heading drift, std (deg) per sqrt(metre driven)", NonNegative());
    v("consistency_match_sigma_m", consistency_match_sigma_m,
      "Consistency gate: std of one scan-to-submap match, translation (m)", Positive());
    v("consistency_match_sigma_deg", consistency_match_sigma_deg,
      "Consistency gate: std of one scan-to-submap match, rotation (deg)", Positive());
    v("consistency_max_chi2", consistency_max_chi2,
      "Consistency gate: largest squared Mahalanobis distance kept (16.27: chi-square, 3 dof, 99.9 "
      "%)",
      Positive());
  }
};

struct GraphOptions {
  int optimise_every_n_nodes = 90;
  int max_iterations = 50;
  int final_max_iterations = 200;  // the optimisation at the end of a log (Cartographer: 200)
  double huber_scale = 100.0;  // 10 (Cartographer) kept loops too weak; 1000 let bad ones in
  double intra_translation_weight = 5e2;
  double intra_rotation_weight = 1.6e3;
  double odometry_translation_weight = 1e3;
  double odometry_rotation_weight = 1e2;
  double local_slam_translation_weight = 1e4;  // 1e5 (Cartographer) held revisits apart on Intel
  double local_slam_rotation_weight = 1e5;
  template <class V> void Visit(V& v) {
    v("optimise_every_n_nodes", optimise_every_n_nodes,
      "Run the global optimisation after this many new nodes (0: only at the end)", AtLeast(0));
    v("max_iterations", max_iterations, "Ceres iterations per optimisation", Positive());
    v("final_max_iterations", final_max_iterations,
      "Ceres iterations of the final optimisation (Optimise())", Positive());
    v("huber_scale", huber_scale, "Huber loss scale on loop closures", Positive());
    v("intra_translation_weight", intra_translation_weight, "Node-in-submap constraints (translation)");
    v("intra_rotation_weight", intra_rotation_weight, "Node-in-submap constraints (rotation)");
    v("odometry_translation_weight", odometry_translation_weight, "Consecutive-node odometry (translation)");
    v("odometry_rotation_weight", odometry_rotation_weight, "Consecutive-node odometry (rotation)");
    v("local_slam_translation_weight", local_slam_translation_weight, "Consecutive-node local matching (translation)");
    v("local_slam_rotation_weight", local_slam_rotation_weight, "Consecutive-node local matching (rotation)");
  }
};

// The noise the published covariances (POSE, SLAM_ANCHORS) assume per constraint. The graph
// weights above are tuning weights: read as square-root information they claim 1e-4 to 1e-5 m
// per constraint, and the simulated lab's POSE covariance came out ~1e5 too tight in variance
// (0.2 mm / 0.005 deg reported, 0.07 m / 1 deg measured). A positive sigma here replaces the
// weight of its kind in the covariance computation only (the optimisation is unchanged); 0 keeps
// the weight.
struct CovarianceOptions {
  double intra_sigma_m = 0, intra_sigma_deg = 0;
  double loop_sigma_m = 0, loop_sigma_deg = 0;
  double odometry_sigma_m = 0, odometry_sigma_deg = 0;
  double local_slam_sigma_m = 0, local_slam_sigma_deg = 0;
  template <class V> void Visit(V& v) {
    v("intra_sigma_m", intra_sigma_m, "Covariance: std of a node-in-submap constraint, translation (0: 1/intra_translation_weight)");
    v("intra_sigma_deg", intra_sigma_deg, "Covariance: std of a node-in-submap constraint, rotation (0: from the weight)");
    v("loop_sigma_m", loop_sigma_m, "Covariance: std of a loop closure, translation (0: from the weight)");
    v("loop_sigma_deg", loop_sigma_deg, "Covariance: std of a loop closure, rotation (0: from the weight)");
    v("odometry_sigma_m", odometry_sigma_m, "Covariance: std of a consecutive-node odometry constraint, translation (0: from the weight)");
    v("odometry_sigma_deg", odometry_sigma_deg, "Covariance: std of a consecutive-node odometry constraint, rotation (0: from the weight)");
    v("local_slam_sigma_m", local_slam_sigma_m, "Covariance: std of a consecutive-node local-matching constraint, translation (0: from the weight)");
    v("local_slam_sigma_deg", local_slam_sigma_deg, "Covariance: std of a consecutive-node local-matching constraint, rotation (0: from the weight)");
  }
  void Validate(Validator& c) const {
    for (double s : {intra_sigma_m, intra_sigma_deg, loop_sigma_m, loop_sigma_deg, odometry_sigma_m,
                     odometry_sigma_deg, local_slam_sigma_m, local_slam_sigma_deg}) {
      c.That(s >= 0, "covariance", "sigmas must be >= 0");
    }
  }
};

// Bounded graph: a submap that maps nothing new is trimmed when it finishes, with the nodes only
// it holds, so that revisits cost no lasting state and the graph grows with the explored area,
// not the mission time (Cartographer's overlapping-submaps trimmer, keeping the oldest map of a
// place instead of the newest). A cell of the new submap s is new while fewer than
// fresh_submaps live submaps older than s - 2 know it; s is trimmed when its new cells add up
// to less than min_fresh_area_m2, unless it sees at least min_new_obstacle_m2 of new obstacle
// (occupied where none of the older submaps has an obstacle within one cell) and fewer than
// obstacle_submaps_per_area_submap submaps per submap that holds area were kept that way:
// the live graph is bounded by the explored area. Past that budget what changed stays on MAP
// through the freed nodes' returns on it. A node kept for a client (SLAM_ANCHORS) outlives its
// submaps. The chain across trimmed nodes is kept by one constraint between the live nodes
// either side.
struct TrimOptions {
  bool enabled = true;
  int fresh_submaps = 1;
  double min_fresh_area_m2 = 1.0;
  double min_new_obstacle_m2 = 0.08;
  double obstacle_submaps_per_area_submap = 0.25;
  double cell_m = 0.2;  // the coverage raster
  template <class V> void Visit(V& v) {
    v("enabled", enabled, "Trim each finished submap that maps nothing new (the graph grows with the explored area, not the mission time)");
    v("fresh_submaps", fresh_submaps,
      "A cell is new while fewer than this many older submaps know it", AtLeast(1));
    v("min_fresh_area_m2", min_fresh_area_m2,
      "A finished submap with less new area than this is trimmed (m^2)", NonNegative());
    v("min_new_obstacle_m2", min_new_obstacle_m2,
      "... unless it sees this much new obstacle (m^2): occupied cells no older submap sees an "
      "obstacle within one raster cell of",
      NonNegative());
    v("obstacle_submaps_per_area_submap", obstacle_submaps_per_area_submap,
      "Submaps kept for new obstacles alone, at most this many per submap that holds new area "
      "(the first three and those kept for it; past that, a new obstacle stays on MAP through "
      "the returns on it, not a submap)",
      NonNegative());
    v("cell_m", cell_m, "Cell size of the coverage raster (m)", Positive());
  }
};

struct InputOptions {
  // Odometry steps faster than these (per second of message time) are rejected as jumps.
  double max_odometry_speed_mps = 5.0;
  double max_odometry_turn_radps = 10.0;
  double max_odometry_jump_m = 1.0;   // regardless of elapsed time
  template <class V> void Visit(V& v) {
    v("max_odometry_speed_mps", max_odometry_speed_mps,
      "Odometry faster than this is a jump (rejected)", Positive());
    v("max_odometry_turn_radps", max_odometry_turn_radps,
      "Odometry turning faster than this is a jump (rejected)", Positive());
    v("max_odometry_jump_m", max_odometry_jump_m,
      "Odometry steps longer than this are jumps (rejected)", Positive());
  }
};

struct SlamOptions {
  ScanOptions scan;
  LocalOptions local;
  LoopClosureOptions loop;
  GraphOptions graph;
  CovarianceOptions covariance;
  InputOptions input;
  TrimOptions trim;
  template <class V> void Visit(V& v) {
    v("scan", scan, "Scan preprocessing");
    v("local", local, "Local SLAM: submaps and scan matching");
    v("loop", loop, "Loop closure: branch-and-bound matching against finished submaps");
    v("graph", graph, "Global pose graph optimisation");
    v("covariance", covariance, "Noise per constraint assumed by the published covariances (POSE, SLAM_ANCHORS)");
    v("input", input, "Input checks");
    v("trim", trim, "Bounded graph: trimming submaps that newer ones cover");
  }
};

}  // namespace slam
}  // namespace sarmap
