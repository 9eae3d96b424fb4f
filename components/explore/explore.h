#pragma once
// Exploration for sarmap-explore, free of LCM.
//
// ReactiveExplorer: the Sales 2014 §4.1.3 behaviour on the (depth-derived) scan. A reading is
// unknown when outside [range_min, range_max - margin]. When the nearest valid range is under
// danger_distance_m (0.6 m) or more than unknown_rate_limit (15 %) of the readings are unknown,
// the robot stops and turns: towards the side (left = positive angles) with the larger mean
// range or, when both means are under low_average_m (1 m), towards the side with more unknown
// readings (possible open space). It keeps turning that way until the way ahead is safe.
//
// FrontierExplorer: frontier-based exploration (Yamauchi 1997) on the occupancy grid: frontier
// cells are known-free cells next to unknown ones, grouped 8-connected; the goal is the
// frontier with the lowest path cost (Dijkstra over free cells inflated by the robot radius)
// minus a size bonus; the path is followed by pure pursuit. The reactive behaviour stays in
// front as the safety layer, and tele-operation overrides both.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/options.h"
#include "common/time.h"
#include "common/transform.h"

namespace sarmap {
namespace explore {

struct Scan {
  double angle_min_rad = 0;
  double angle_increment_rad = 0;
  double range_min_m = 0;
  double range_max_m = 0;
  std::vector<float> ranges_m;
};

struct Velocity {
  double linear_mps = 0;
  double angular_radps = 0;
  std::string source;  // "reactive", "frontier", "teleop", "stop"
};

struct ReactiveOptions {
  double danger_distance_m = 0.6;
  double unknown_rate_limit = 0.15;
  double low_average_m = 1.0;
  double max_range_margin_m = 1.0;  // readings above range_max - margin are unknown (Sales)
  double forward_speed_mps = 0.25;
  double turn_speed_radps = 0.5;
  template <class V>
  void Visit(V& v) {
    v("danger_distance_m", danger_distance_m, "stop and turn when the nearest valid range is below this");
    v("unknown_rate_limit", unknown_rate_limit, "stop and turn when this fraction of readings is unknown");
    v("low_average_m", low_average_m, "when both sides' mean range is below this, turn to the side with more unknown");
    v("max_range_margin_m", max_range_margin_m, "readings above range_max minus this are unknown");
    v("forward_speed_mps", forward_speed_mps, "speed when the way is safe");
    v("turn_speed_radps", turn_speed_radps, "turn rate of the avoiding behaviour");
  }
  void Validate(common::Validator& check) const {
    check.Positive("danger_distance_m", danger_distance_m);
    check.InRange("unknown_rate_limit", unknown_rate_limit, 0.0, 1.0);
    check.Positive("low_average_m", low_average_m);
    check.NonNegative("max_range_margin_m", max_range_margin_m);
    check.Positive("forward_speed_mps", forward_speed_mps);
    check.Positive("turn_speed_radps", turn_speed_radps);
  }
};

struct ScanMetrics {
  double min_valid_m = 0;    // +inf when no valid reading
  double unknown_rate = 0;
  double mean_left_m = 0, mean_right_m = 0;
  double unknown_left = 0, unknown_right = 0;  // rates per side
};

ScanMetrics AnalyseScan(const Scan& scan, const ReactiveOptions& options);

class ReactiveExplorer {
 public:
  explicit ReactiveExplorer(const ReactiveOptions& options) : options_(options) {}
  // The command for this scan; `danger` tells whether the avoiding behaviour is active.
  Velocity Step(const Scan& scan, bool* danger = nullptr);

 private:
  ReactiveOptions options_;
  int turning_ = 0;  // +1 left, -1 right, 0 not turning
};

struct Grid {
  int width = 0, height = 0;
  double resolution_m = 0.05;
  double origin_x_m = 0, origin_y_m = 0;  // cell (0, 0) corner; the grid is axis-aligned
  std::vector<int8_t> cells;              // -1 unknown, 0..100 occupancy, row-major
  int8_t at(int x, int y) const { return cells[static_cast<size_t>(y) * width + x]; }
  bool Contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  Eigen::Vector2i CellOf(const Eigen::Vector2d& p) const;
  Eigen::Vector2d CentreOf(int x, int y) const;
};

struct FrontierOptions {
  int min_frontier_cells = 5;
  double robot_radius_m = 0.25;
  int free_threshold = 25;      // cells below are free
  int occupied_threshold = 65;  // cells above are occupied
  double size_weight_m = 0.05;  // metres of path a frontier cell is worth
  double goal_reached_m = 0.35;
  double lookahead_m = 0.6;
  double max_linear_mps = 0.3;
  double max_angular_radps = 0.8;
  double blacklist_radius_m = 0.5;  // around goals that could not be reached
  template <class V>
  void Visit(V& v) {
    v("min_frontier_cells", min_frontier_cells, "smaller frontiers are ignored");
    v("robot_radius_m", robot_radius_m, "obstacles are inflated by this");
    v("free_threshold", free_threshold, "occupancy below this is free");
    v("occupied_threshold", occupied_threshold, "occupancy above this is an obstacle");
    v("size_weight_m", size_weight_m, "path metres one frontier cell is worth");
    v("goal_reached_m", goal_reached_m, "distance at which a goal counts as reached");
    v("lookahead_m", lookahead_m, "pure-pursuit lookahead");
    v("max_linear_mps", max_linear_mps, "speed limit while following a path");
    v("max_angular_radps", max_angular_radps, "turn-rate limit while following a path");
    v("blacklist_radius_m", blacklist_radius_m, "frontiers this close to an abandoned goal are skipped");
  }
  void Validate(common::Validator& check) const {
    check.That(min_frontier_cells >= 1, "min_frontier_cells", "must be >= 1");
    check.NonNegative("robot_radius_m", robot_radius_m);
    check.That(free_threshold >= 0 && free_threshold < occupied_threshold && occupied_threshold <= 100,
               "occupied_threshold", "need 0 <= free_threshold < occupied_threshold <= 100");
    check.NonNegative("size_weight_m", size_weight_m);
    check.Positive("goal_reached_m", goal_reached_m);
    check.Positive("lookahead_m", lookahead_m);
    check.Positive("max_linear_mps", max_linear_mps);
    check.Positive("max_angular_radps", max_angular_radps);
    check.NonNegative("blacklist_radius_m", blacklist_radius_m);
  }
};

struct Frontier {
  std::vector<Eigen::Vector2i> cells;
  Eigen::Vector2d goal_m;  // the frontier cell closest (by path) to the robot
  double path_cost_m = 0;
};

class FrontierExplorer {
 public:
  explicit FrontierExplorer(const FrontierOptions& options) : options_(options) {}
  void SetMap(Grid grid);
  // All reachable frontiers from `robot_xy`, best first.
  std::vector<Frontier> Frontiers(const Eigen::Vector2d& robot_xy) const;
  // The command towards the current (or a new) goal; nullopt when nothing is left to explore.
  std::optional<Velocity> Step(const common::Rigid2d& map_from_base);
  // Marks the current goal unreachable (e.g. the safety layer kept blocking it).
  void AbandonGoal();
  const std::vector<Eigen::Vector2d>& path() const { return path_; }
  bool has_map() const { return grid_.width > 0; }

 private:
  // Dijkstra from the robot over traversable cells: cost per cell, and parents for paths.
  void Plan(const Eigen::Vector2d& robot_xy, std::vector<double>* cost, std::vector<int>* parent) const;
  bool Traversable(int x, int y) const;

  FrontierOptions options_;
  Grid grid_;
  std::vector<uint8_t> blocked_;  // inflated obstacles
  std::vector<Eigen::Vector2d> path_;
  std::optional<Eigen::Vector2d> goal_;
  std::vector<Eigen::Vector2d> blacklist_;
};

struct TeleopCommand {
  common::Utime utime = 0;
  bool override_active = false;
  bool emergency_stop = false;
  double linear_mps = 0, angular_radps = 0;
};

struct ExploreOptions {
  std::string mode = "frontier";  // reactive | frontier
  double teleop_timeout_s = 0.5;  // the operator's override ends this long after their last message
  ReactiveOptions reactive;
  FrontierOptions frontier;
  template <class V>
  void Visit(V& v) {
    v("mode", mode, "reactive (Sales 2014) or frontier (map-driven, reactive as safety layer)");
    v("teleop_timeout_s", teleop_timeout_s, "operator override ends this long after the last TELEOP");
    v("reactive", reactive, "reactive behaviour");
    v("frontier", frontier, "frontier exploration");
  }
  void Validate(common::Validator& check) const {
    check.OneOf("mode", mode, {"reactive", "frontier"});
    check.Positive("teleop_timeout_s", teleop_timeout_s);
  }
};

// Tele-operation over everything; then the reactive layer whenever it sees danger; then the
// frontier explorer (mode frontier, with a map and a pose); else the reactive behaviour.
class ExploreController {
 public:
  explicit ExploreController(const ExploreOptions& options)
      : options_(options), reactive_(options.reactive), frontier_(options.frontier) {}
  void OnTeleop(const TeleopCommand& command) { teleop_ = command; }
  void OnMap(Grid grid) { frontier_.SetMap(std::move(grid)); }
  void OnPose(const common::Rigid2d& map_from_base) { pose_ = map_from_base; }
  Velocity OnScan(common::Utime utime, const Scan& scan);
  const FrontierExplorer& frontier() const { return frontier_; }
  bool finished() const { return finished_; }

 private:
  ExploreOptions options_;
  ReactiveExplorer reactive_;
  FrontierExplorer frontier_;
  std::optional<TeleopCommand> teleop_;
  std::optional<common::Rigid2d> pose_;
  int blocked_scans_ = 0;
  bool finished_ = false;
};

}  // namespace explore
}  // namespace sarmap
