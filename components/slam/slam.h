#pragma once
// 2D graph SLAM after the design of Hess et al. 2016 ("Real-Time Loop Closure in 2D LIDAR
// SLAM", Cartographer):
//  - local SLAM: each scan is matched against the older of two overlapping submaps
//    (probability grids) by a correlative search and a Ceres refinement, starting from the
//    odometry prediction; scans that moved enough become graph nodes and are inserted into
//    both active submaps; a submap is finished after 2 * scans_per_submap insertions.
//  - global SLAM: a pose graph of nodes and submaps with node-in-submap constraints (from
//    local SLAM), consecutive-node odometry and local-matching constraints, and loop closures
//    found by branch-and-bound correlative matching of nodes against finished submaps,
//    verified by their mean matched probability; optimised with Ceres (SPARSE_NORMAL_CHOLESKY,
//    Huber loss on loop closures).
// No LCM here: the node and the offline runner feed it.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <unordered_set>
#include <vector>

#include "slam/active_submaps.h"
#include "slam/grid.h"
#include "slam/loop_consistency.h"
#include "slam/motion_filter.h"
#include "slam/odometry_buffer.h"
#include "slam/packed_points.h"
#include "slam/pose_extrapolator.h"
#include "slam/pose_graph.h"
#include "slam/relations.h"
#include "slam/scan_matcher.h"
#include "slam/slam_options.h"

namespace sarmap {
namespace slam {

// One scan with its own geometry: beam i points at angle_min_rad + i * angle_increment_rad in
// the laser frame. Consecutive scans may differ in start angle, increment and beam count
// (interlacing scanners, drivers that drop end beams).
struct LaserScan {
  double time_s = 0;
  double angle_min_rad = 0;
  double angle_increment_rad = 0;
  float range_min_m = 0;
  float range_max_m = 0;  // a reading outside [min, max] or not finite is "no return"
  std::vector<float> ranges_m;
  // base_from_laser of this scan (CARMEN ROBOTLASER1 lines carry it); unset: slam.scan.laser_*.
  bool has_base_from_laser = false;
  Rigid2d base_from_laser;
};

struct ScanResult {
  bool accepted = false;
  std::string reason;     // why rejected
  Rigid2d map_from_base;  // global pose of the scan
  int node_id = -1;       // the node of this scan, else the latest node
  bool is_node = false;
  bool optimised = false;    // a global optimisation ran after this scan
  bool loop_closed = false;  // ... and it included new loop closures
  double match_score = 0;
  bool waiting_for_odometry = false;  // not used: restarted, the first odometry has not come yet
};

struct SlamStats {
  int64_t scans = 0, nodes = 0, submaps = 0;
  int64_t rejected_scans = 0, rejected_odometry = 0, reordered_odometry = 0, reordered_scans = 0;
  int64_t stopped_scans = 0;  // matched at the stop pose (unchanged_odometry_means_stopped)
  int64_t scans_waiting_for_odometry = 0;  // after a restart, before the first odometry
  int64_t loop_searches = 0, loop_closures = 0;
  int64_t loop_closures_inconsistent = 0;  // found, then rejected by the consistency gate
  int64_t loop_closures_at_window_edge = 0;  // found on the search window's boundary, rejected
  int64_t precomputations_built = 0;       // branch-and-bound stacks built (cache misses)
  int64_t optimisations = 0;
  int64_t submaps_trimmed = 0, nodes_trimmed = 0;  // trim.enabled
  // trim.enabled: finished submaps kept for their new area (new obstacles or not), for new
  // obstacles only, and trimmed with new obstacles because the budget for those was spent.
  int64_t submaps_kept_new_area = 0, submaps_kept_new_obstacles = 0;
  int64_t submaps_trimmed_over_obstacle_budget = 0;
  double optimise_seconds = 0, loop_seconds = 0, local_seconds = 0;
};

// An occupancy grid for output: -1 unknown, 0..100 occupied probability; row 0 at origin.
struct OccupancyMap {
  double resolution_m = 0.05;
  int width = 0, height = 0;
  double origin_x_m = 0, origin_y_m = 0;  // lower-left corner of cell (0, 0)
  std::vector<int8_t> cells;
};

class Slam {
 public:
  explicit Slam(const SlamOptions& options);
  ~Slam();

  // Odometry odom_from_base at `time_s`, in time order. Returns false (and counts) when it is
  // rejected as a jump or not finite; `why` says why.
  bool AddOdometry(double time_s, const Rigid2d& odom_from_base, std::string* why = nullptr);
  // Scans in time order, each with its own geometry. Garbage (negative/NaN ranges, fewer than 2
  // or more than 100000 beams, bad angles) is rejected and counted.
  ScanResult AddScan(const LaserScan& scan);
  // Runs the global optimisation now (e.g. at the end of a log).
  void Optimise();

  // Localisation only: no new nodes or submaps; scans are matched against the finished
  // submaps of a loaded map.
  void SetLocalisationOnly(bool on) { localisation_only_ = on; }
  bool localisation_only() const { return localisation_only_; }
  // Localisation only: where to start (the first scan is searched around it); by default the
  // last pose of the saved map.
  void SetLocalisationStart(const Rigid2d& map_from_base) {
    extrapolator_.Start(map_from_base);  // a new start: no time order with the saved state
    have_scan_since_load_ = false;
  }

  // Global pose of every accepted scan (time order).
  std::vector<StampedPose2> Trajectory() const;
  // What SLAM's data takes, by part (container capacities; the allocator's own overhead and
  // the optimiser's transient problem not counted): what grows with mission time and what
  // with the mapped area.
  struct MemoryUsage {
    size_t submap_grids = 0;     // live submaps' grids and their trimming samples
    size_t precomputations = 0;  // cached loop-closure precomputation stacks
    size_t live_nodes = 0;       // live nodes: record, loop points and range data
    size_t trimmed_nodes = 0;    // trimmed nodes: record and the returns they keep
    size_t trimmed_submaps = 0;  // trimmed submaps: record and node list
    size_t graph = 0;            // constraints and the nodes' and submaps' global poses
    size_t trajectory = 0;       // every accepted scan's pose
    size_t Total() const {
      return submap_grids + precomputations + live_nodes + trimmed_nodes + trimmed_submaps + graph +
             trajectory;
    }
  };
  MemoryUsage Memory() const;
  const SlamStats& stats() const { return stats_; }
  // Node ids run 0..num_nodes()-1; a trimmed node keeps its id and the pose it had when it was
  // trimmed.
  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  bool NodeTrimmed(int id) const { return nodes_[id].trimmed; }
  int num_live_nodes() const { return num_nodes() - static_cast<int>(stats_.nodes_trimmed); }
  int num_live_submaps() const {
    return static_cast<int>(submaps_.size() - stats_.submaps_trimmed);
  }
  // Live nodes every submap of which is trimmed: live only because a client keeps them.
  int num_nodes_kept_for_anchors() const { return static_cast<int>(orphan_nodes_.size()); }
  // SLAM_ANCHORS: of the nodes clients request, those that exist and are live are kept (replaces
  // the last set). A kept node outlives its submaps: trimming takes them as if it were not there,
  // and the node stays in the graph, tied to its live neighbours by TRIMMED_CHAIN constraints
  // (and to later submaps by loop closures), so that its pose and covariance keep following the
  // graph. A node that outlived its submaps and is no longer kept is trimmed now. Returns the
  // latest node followed by the kept ones: the nodes of one joint covariance. Needs at least one
  // node.
  std::vector<int> HoldAnchors(const std::vector<int64_t>& requested);
  Rigid2d NodePose(int id) const { return node_global_[id]; }
  double NodeTime(int id) const { return nodes_[id].time_s; }
  int64_t optimisation_id() const { return stats_.optimisations; }
  // Latest scan's global pose.
  Rigid2d CurrentPose() const;

  // Joint covariance (3k x 3k) of the nodes' (x, y, yaw) in the map frame.
  bool JointCovariance(const std::vector<int>& node_ids, Eigen::MatrixXd* covariance) const;

  // The map, rendered from every node's scan at its optimised pose.
  OccupancyMap RenderMap() const;
  // The map composed from the live submaps' grids at their optimised poses, with the returns
  // trimmed nodes keep drawn on it. The even-numbered submaps hold every node once, and so do
  // the odd-numbered ones (but for the first scans_per_submap nodes), so each parity's sum of
  // log-odds is the evidence RenderMap() gathers from the nodes; a cell takes the parity that
  // knows it, or the one with more evidence (trimming takes submaps from either). Its cost
  // grows with the live submaps' area, not with the nodes.
  OccupancyMap ComposeMap() const;
  // The map as a live node publishes it (scan.map_source): ComposeMap(), or RenderMap() with
  // the drawing kept between calls. Nodes added since the last call are drawn into it; it is
  // drawn again from every node only after Load() or when an optimisation has moved a drawn
  // node's returns by more than scan.map_redraw_shift_cells, bounded by |translation change| +
  // |yaw change| x the scan's reach. Between redraws it equals RenderMap() up to that shift,
  // except that a node trimmed after it was drawn stays drawn with its whole scan.
  OccupancyMap DrawMap();
  struct MapDrawingStats {
    int64_t draws = 0;
    int64_t redraws = 0;  // map_source nodes: drawn from every node
    int64_t nodes_drawn = 0;
    double seconds = 0;  // in DrawMap
  };
  const MapDrawingStats& map_drawing_stats() const { return map_drawing_stats_; }

  // Our own pose-graph file (everything needed to continue mapping or to localise);
  // written to a temporary file and renamed, so a crash never leaves a broken file.
  void Save(const std::string& path) const;
  // Replaces the state with a saved one. Throws std::runtime_error on a bad file.
  void Load(const std::string& path);

 private:
  struct Submap {
    Rigid2d local_pose;  // local_from_submap (translation only)
    std::unique_ptr<ProbabilityGrid> grid;
    int num_inserted = 0;
    bool finished = false;
    bool trimmed = false;  // its grid is freed and its constraints removed
    // Finished: its known cells every trim.cell_m and its occupied cells (TrimIfCovered), as
    // grid cell indices y * width + x, taken once.
    bool samples_ready = false;
    std::vector<uint32_t> known_samples, occupied_samples;
    std::vector<int> nodes;
    // Loop-closure sampler state (fixed ratio).
    int64_t pulses = 0, samples = 0;
  };
  struct NodeData {
    bool has_odometry = false;
    int odom_segment = -1;
    Rigid2d odom_pose;
    PointCloud loop_points;  // base frame
    PackedRangeData range_data;  // base frame (for map rendering), 16-bit
    std::vector<int> submaps;  // the submaps it was inserted into
  };
  // A live node holds its scan in `data`. A trimmed node (every submap of it trimmed) keeps its
  // time and poses, and `data` only for its returns on obstacles no live submap holds
  // (range_data.hits, no misses; drawn on MAP at its last pose), null when there are none: a
  // long mission leaves tens of thousands of trimmed nodes, each a few dozen bytes.
  struct Node {
    double time_s = 0;
    Rigid2d local_pose;
    bool trimmed = false;
    std::unique_ptr<NodeData> data;
  };
  // Every accepted scan's pose, 24 bytes (a long mission keeps about 50,000 an hour): relative
  // to its node (float is exact to well under a micrometre there), or, without a node, in the
  // local frame (global in localisation-only mode).
  struct ScanRecord {
    double time_s;
    float x_m, y_m, yaw_rad;
    int32_t node_id;
    Rigid2d pose() const { return Rigid2d(x_m, y_m, yaw_rad); }
  };
  // The record of a scan at `pose` (local frame, or global without a node) beside node_id.
  ScanRecord MakeScanRecord(double time_s, const Rigid2d& pose, int node_id) const;

  bool CheckScan(const LaserScan& scan, std::string* why);
  void ScanToRangeData(const LaserScan& scan, RangeData* data) const;
  // AddScan after the time-order check: `scan.time_s` is the processing time, `stamp_s` the
  // scan's own stamp (kept in the trajectory).
  ScanResult AddScanInOrder(const LaserScan& scan, double stamp_s);
  Rigid2d MatchLocal(const ProbabilityGrid& grid, const PointCloud& points,
                     const Rigid2d& predicted, double* score) const;
  ScanResult AddScanLocalisation(const LaserScan& scan, const RangeData& data,
                                 const PointCloud& points);
  int AddNode(double time_s, const Rigid2d& local_pose, const RangeData& base_data,
              const PointCloud& loop_points, const std::vector<int>& inserted_into);
  // A new active submap whose grid starts at `local_pose` (translation only).
  void StartSubmap(const Rigid2d& local_pose);
  void FinishSubmap(int submap_id);
  // trim.enabled: trims a just-finished submap that older ones cover (TrimOptions). Submaps
  // 0..kOwnChain are never judged (submap 0 holds the map frame; each is s - 1 or s - 2 of the
  // next, the same pass).
  static constexpr int kOwnChain = 2;
  void TrimIfCovered(int submap_id);
  // `new_obstacles`: the raster cells (trim.cell_m, map frame) where the submap saw an obstacle
  // no older submap holds; a freed node keeps its returns in them.
  void TrimSubmap(int submap_id, const std::unordered_set<int64_t>& new_obstacles);
  // Whether some submap the live node was inserted into is live.
  bool InLiveSubmap(int node_id) const;
  // Frees the nodes (ascending, live) and every constraint on them; each node keeps its returns
  // in `new_obstacles`. Each run of trimmed nodes between live nodes p < q becomes one
  // TRIMMED_CHAIN constraint p -> q at the graph's current estimate.
  void TrimNodes(const std::vector<int>& node_ids,
                 const std::unordered_set<int64_t>& new_obstacles);
  // retained_obstacles_ from the returns the trimmed nodes keep (after a load).
  void RebuildRetainedObstacles();
  // A just-trimmed node keeps only `kept_hits` (none: no data at all).
  static void ReleaseTrimmedData(Node* node, PointCloud kept_hits);
  // The map-frame circle around the submap's grid.
  void SubmapCircle(int submap_id, Eigen::Vector2d* centre_m, double* radius_m) const;
  // The map-frame raster cells (trim.cell_m) the submap's grid knows and those it holds an
  // obstacle in (sorted keys).
  void KnownCells(int submap_id, std::vector<int64_t>* known, std::vector<int64_t>* occupied);
  bool SampleSubmap(Submap* submap);
  bool TryLoopClosure(int node_id, int submap_id);
  // Whether a loop closure (submap_from_node `measured`) agrees with the graph's current
  // estimate within local SLAM's drift between the node and the submap (loop.consistency_*).
  bool ConsistentWithGraph(int node_id, int submap_id, const Rigid2d& measured);
  const PrecomputationStack& Precomputation(int submap_id);
  void RunOptimisation(int max_iterations = 0);  // 0: graph.max_iterations
  // Draws node `id`'s data (if any) into `grid` at its global pose; returns the scan's reach
  // (largest distance of a point from the node's pose), -1 without data.
  float DrawNode(int id, ProbabilityGrid* grid) const;

  SlamOptions options_;
  bool localisation_only_ = false;
  bool have_scan_since_load_ = false;
  SlamStats stats_;

  OdometryBuffer odometry_;
  MotionFilter motion_filter_;  // which scans become nodes
  PoseExtrapolator extrapolator_;  // the matched scans' track and the next scan's prediction

  // Local SLAM.
  std::vector<Submap> submaps_;
  ActiveSubmaps active_submaps_;  // which of submaps_ take new nodes

  // Global SLAM.
  std::deque<Node> nodes_;  // a deque: no doubling copy of tens of thousands of nodes
  std::vector<Rigid2d> node_global_, submap_global_;
  std::vector<Constraint> constraints_;
  ChainDrift chain_drift_;  // drift prefix sums over nodes_' local poses (extended on demand)
  Rigid2d global_from_local_;
  int nodes_since_optimisation_ = 0;
  int64_t loop_closures_at_last_optimisation_ = 0;
  std::deque<ScanRecord> scans_;
  std::list<std::pair<int, std::unique_ptr<PrecomputationStack>>> precomputations_;
  std::vector<int> kept_nodes_;  // sorted
  // Live nodes whose submaps are all trimmed (ascending): kept for a client, trimmed once it
  // releases them (HoldAnchors). After a load they are found again from the nodes.
  std::vector<int> orphan_nodes_;
  // Raster cells (trim.cell_m) of the returns trimmed nodes keep: obstacles no live submap holds.
  std::unordered_set<int64_t> retained_obstacles_;
  // Raster cells (trim.cell_m) trimmed submaps knew and no older live submap did (each under
  // min_fresh_area_m2): they count as known by one submap, so that a later pass over them does
  // not find them new again.
  std::unordered_set<int64_t> retained_known_;

  // DrawMap's drawing: the grid, and per drawn node the pose it was drawn at and its reach.
  struct DrawnNode {
    Rigid2d pose;
    float reach_m = 0;
  };
  std::unique_ptr<ProbabilityGrid> map_drawing_;
  std::vector<DrawnNode> drawn_nodes_;
  MapDrawingStats map_drawing_stats_;
};

}  // namespace slam
}  // namespace sarmap
