#pragma once
// Mission metrics of an autonomous exploration mission in the simulator, computed from the
// messages of the mission in the order they were received, so that `sarmap-log report` (fed
// from a log) and an in-process closed-loop benchmark (fed from its own bus) give the same
// figures.
//
// Inputs (channel: type), each passed with its receive time `utime` (µs, any clock, non-
// decreasing across all inputs; the log's event time in a log):
//   SIM_TRUTH      sim_truth_t        the robot's true pose, its start pose, the distance truly
//                                     driven, the contacts, the true people (world frame)
//   SIM_FLOOR      occupancy_grid_t   world frame: 0 floor the robot can reach, 100 obstacle
//                                     footprint, -1 neither
//   MAP            occupancy_grid_t   SLAM's map, map frame, possibly zstd-compressed
//   PEOPLE_MAP     people_map_t       map frame
//   EXPLORE_STATUS explore_status_t   map frame; absent in scripted missions
//
// Frames. SLAM's map frame is the robot's start pose: the odometry starts at the identity
// (sim/robot.cc) and SLAM's first scan is placed at the identity with no prior, so before any
// motion POSE is the identity. Hence, with s = start_pose = (x_s, y_s, yaw_s),
//   world_from_map(p) = R(yaw_s) p + (x_s, y_s),     map_from_world = world_from_map^-1,
// exact even when the robot never moves (a trail fit is then undetermined). SLAM's drift is
// not corrected: it shows as position error and as mapped cells off the true floor. (SLAM in
// localisation-only mode keeps a saved map's frame instead; this alignment then does not hold.)
//
// Definitions (t is measured from the first SIM_TRUTH; all areas in m^2):
//   reachable_m2     (SIM_FLOOR cells == 0) * resolution^2, from the last SIM_FLOOR.
//   mapped_m2        reachable cells whose centre c_w, mapped to c_m = map_from_world(c_w),
//                    falls in a MAP cell with value >= 0 (free or occupied, i.e. observed), times
//                    the floor cell area; cell (col, row) of a grid covers
//                    origin + R(origin_yaw) [col, col+1) x [row, row+1) * resolution.
//   mapped_fraction  mapped_m2 / reachable_m2.
//   coverage curve   (t, mapped_m2, fraction) for a MAP that arrives at least
//                    coverage_interval_s after the previous point, plus the last MAP; each point
//                    uses the SIM_FLOOR and truth known when that MAP arrived.
//   person found     true person i, at w_i in the world, is matched in a PEOPLE_MAP when the
//                    one-to-one matching (MatchPeople: pairs within match_radius_m of
//                    map_from_world(w_i), closest first, each person used once) gives it a mapped
//                    person. found: matched in the last PEOPLE_MAP; found_after_s: t of the first
//                    PEOPLE_MAP in which it was matched (only when found); cues: the matched
//                    person's cues in the last PEOPLE_MAP; dropped: matched once, not at the end.
//   distance_m, collisions   the last SIM_TRUTH's.
//   stuck            at truth sample k (time t_k) the robot is stuck when the truth covers the
//                    trailing stuck_window_s (a sample at or before t_k - window exists), every
//                    sample j in [the last sample at or before t_k - window, k] has
//                    |p_j - p_k| < stuck_distance_m and |wrap(yaw_j - yaw_k)| < stuck_turn_rad,
//                    and the last EXPLORE_STATUS says exploring, seeking_sound, recovering or
//                    returning (home, finished, override: the robot is meant to stand).
//                    stuck_s = sum of t_k - t_{k-1} over consecutive samples both stuck;
//                    longest_stuck_s the longest such run. A stop of T >= window seconds
//                    counts about T - window (plus the time the robot is within
//                    stuck_distance_m of the stop while arriving and leaving). Without any
//                    EXPLORE_STATUS stuck is not judged (std::nullopt).
//   confined         at truth sample k the robot is confined when the truth covers the
//                    trailing confined_window_s, every sample j in it has
//                    |p_j - p_k| < confined_radius_m, and the last EXPLORE_STATUS judges stuck
//                    as above: it may move and turn, but goes nowhere (a robot that backs off,
//                    turns and drives into the same doorway again and again). A run of
//                    consecutive confined samples lasts from the window start of its first
//                    sample to its last sample; longest_confined_s is the longest run (nullopt
//                    without EXPLORE_STATUS).
//   came_home        an EXPLORE_STATUS said home, and the last truth position is within
//                    home_radius_m of the start pose; home_after_s = t of the first such status.
//   mission_s        the last input's time - the first truth's.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/transform.h"
#include "sarmap/explore_status_t.hpp"
#include "sarmap/mapped_person_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/sim_truth_t.hpp"

namespace sarmap {
namespace logtools {

struct MissionMetricsOptions {
  double match_radius_m = 0.5;       // a mapped person this close to a true one found them
  double coverage_interval_s = 5.0;  // at most one coverage point per this much time
  double stuck_window_s = 10.0;
  double stuck_distance_m = 0.15;  // moved less than this over the window ...
  double stuck_turn_rad = 0.5;     // ... and turned less than this: stuck
  double confined_window_s = 60.0;
  double confined_radius_m = 1.0;  // stayed this close to where it is over the window: confined
  double home_radius_m = 0.5;      // ends this close to the start pose: at home
};

// The one-to-one matching of true people (positions already in the map frame) to mapped ones:
// all pairs within radius_m, closest first, each person used once. Returns, per true person,
// the index into `mapped` or -1; `distance_m` (optional) gets the matched distances.
std::vector<int> MatchPeople(const std::vector<Eigen::Vector2d>& truth_in_map,
                             const std::vector<sarmap::mapped_person_t>& mapped, double radius_m,
                             std::vector<double>* distance_m = nullptr);

// SLAM's trail error: RMS of |map_from_world * truth - estimate| over time-matched robot
// positions (estimate in the map frame, truth in the world frame). With map_from_world the start
// pose's inverse (MissionMetricsResult::world_from_map) this is the report's "robot trail
// residual". 0 without pairs.
double TrailResidualRms(
    const common::Rigid2d& map_from_world,
    const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& estimate_truth);

struct CoveragePoint {
  double time_s = 0;
  double mapped_m2 = 0;
  double fraction = 0;
};

struct PersonOutcome {
  int64_t truth_id = -1;
  std::string name;
  Eigen::Vector2d world_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d map_m = Eigen::Vector2d::Zero();  // map_from_world(world_m)
  bool found = false;
  std::optional<double> found_after_s;
  int cues = 0;  // mapped_person_t::CUE_* of the match in the last PEOPLE_MAP
  int64_t person_id = -1;
  double error_m = 0;
  bool dropped = false;
};

struct MissionMetricsResult {
  bool have_truth = false;
  common::Rigid2d world_from_map;  // the start pose
  double mission_s = 0;
  // Coverage: set when SIM_FLOOR, SIM_TRUTH and MAP were all received.
  std::optional<double> reachable_m2;
  std::optional<double> mapped_m2;
  std::optional<double> mapped_fraction;
  std::vector<CoveragePoint> coverage;
  std::vector<PersonOutcome> people;  // one per true person of the last SIM_TRUTH
  double distance_m = 0;
  int collisions = 0;
  std::optional<double> stuck_s, longest_stuck_s;  // nullopt without EXPLORE_STATUS
  std::optional<double> longest_confined_s;        // nullopt without EXPLORE_STATUS
  bool came_home = false;
  std::optional<double> home_after_s;
  std::optional<double> home_error_m;  // the last truth position's distance from the start pose
  std::string last_explore_state;      // "" without EXPLORE_STATUS
};

class MissionMetrics {
 public:
  explicit MissionMetrics(const MissionMetricsOptions& options = {});

  void OnTruth(int64_t utime, const sarmap::sim_truth_t& truth);
  void OnFloor(int64_t utime, const sarmap::occupancy_grid_t& floor);
  void OnMap(int64_t utime, const sarmap::occupancy_grid_t& map);
  void OnPeopleMap(int64_t utime, const sarmap::people_map_t& people);
  void OnExploreStatus(int64_t utime, const sarmap::explore_status_t& status);

  // The figures so far (the last MAP completes the coverage curve when it is not on it yet).
  MissionMetricsResult Result() const;

  // The reachable floor cells not on a known MAP cell, as centres in the map frame, for
  // drawing what was missed; empty without SIM_FLOOR, SIM_TRUTH or MAP.
  std::vector<Eigen::Vector2d> UnmappedFloorInMap() const;
  double floor_resolution_m() const { return floor_resolution_m_; }
  // The floor grid's axes in the map frame: start yaw^-1 + the floor's origin_yaw.
  double floor_yaw_in_map_rad() const { return map_from_world_.yaw_rad() + floor_yaw_rad_; }
  const std::optional<sarmap::explore_status_t>& last_explore_status() const { return explore_; }
  const MissionMetricsOptions& options() const { return options_; }

 private:
  struct Sample {
    int64_t utime;  // window bounds compared in µs, exactly
    Eigen::Vector2d position_m;
    double yaw_rad;
  };
  struct Grid {
    double resolution_m = 0, origin_x_m = 0, origin_y_m = 0, origin_yaw_rad = 0;
    int width = 0, height = 0;
    std::vector<int8_t> cells;
    bool Known(const Eigen::Vector2d& p) const;  // p in the grid's frame
  };

  double Since(int64_t utime) const;  // seconds since the first truth
  void Touch(int64_t utime);
  // Reachable floor cells on a known cell of the last MAP; -1 when not computable.
  int64_t MappedCells() const;
  void AddCoveragePoint(double t_s);

  MissionMetricsOptions options_;
  std::optional<int64_t> first_truth_utime_;
  std::optional<int64_t> last_utime_;
  std::optional<sarmap::sim_truth_t> truth_;
  common::Rigid2d map_from_world_;
  std::vector<Eigen::Vector2d> floor_world_;  // centres of the reachable cells
  double floor_resolution_m_ = 0, floor_yaw_rad_ = 0;
  bool have_floor_ = false;
  std::optional<Grid> map_;
  double map_time_s_ = 0;
  bool map_on_curve_ = false;
  std::vector<CoveragePoint> coverage_;
  // People: first time each true person id was matched, and the last PEOPLE_MAP.
  std::vector<std::pair<int64_t, double>> first_matched_s_;
  std::optional<sarmap::people_map_t> people_;
  // Stuck.
  std::deque<Sample> window_;  // truth samples of the trailing window, oldest first
  bool was_stuck_ = false;
  double stuck_s_ = 0, run_s_ = 0, longest_stuck_s_ = 0;
  // Confined: a longer window of positions, and the start of the current run.
  std::deque<Sample> confined_window_;
  std::optional<int64_t> confined_since_utime_;
  double longest_confined_s_ = 0;
  std::optional<sarmap::explore_status_t> explore_;
  std::optional<double> home_s_;
};

}  // namespace logtools
}  // namespace sarmap
