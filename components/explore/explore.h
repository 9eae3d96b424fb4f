#pragma once
// Exploration for sarmap-explore, free of LCM.
//
// ReactiveExplorer: the Sales 2014 §4.1.3 behaviour on the (depth-derived) scan. A reading is
// unknown when it carries no information (0, NaN, below range_min) or lies in the unreliable
// band above range_max - margin; +inf (no return) is free space up to range_max. When the
// nearest valid range is under danger_distance_m (0.6 m) or more than unknown_rate_limit (15 %)
// of the readings are unknown, the robot stops and turns: towards the side (left = positive
// angles) with the larger mean range or, when both means are under low_average_m (1 m), towards
// the side with more unknown readings. It keeps turning that way until the way ahead is safe.
//
// SafetyLayer: limits the forward speed of any command to what the scan and the map allow in a
// corridor of the robot's width ahead (stop below stop_distance_m, full speed beyond
// slow_distance_m, linear in between). It never turns the robot: the planner chooses where to
// go, the safety layer only decides how fast forward is safe. A corridor whose readings carry
// no information (an obstacle nearer than the camera's minimum range blanks the columns) counts
// as blocked.
//
// ExploreController: the mission. Tele-operation first (receive-time dead man, clamped), then:
//   look_around -> exploring <-> seeking_sound -> returning -> home
// (returning -> exploring when frontiers are reached again on the way home after exploration
// ended for want of them)
// with recovering entered from any driving state when progress stops. Goals are frontiers
// (path cost minus a size bonus, kept until reached, gone or clearly beaten) or, in
// sound_guided mode, people heard but not yet seen, and with sound.voices the voices on SOUND_MAP
// nobody on PEOPLE_MAP explains (a cell in view of them, or in range when they are behind
// cover). Paths come from ExploreMap's planner and are followed by pure pursuit, its target
// kept where the straight line to it keeps the path's clearance (no corner cut).
// Stuck recovery: back off (when the map behind is free), turn towards the open side, replan; a
// goal that needs two recoveries is blacklisted for blacklist_expiry_s. A forward command that
// does not move the robot marks an obstacle the sensors miss (glass) in the explorer's map.
// Recoveries with no plan out, or repeating in one place, escape on the scan for a while.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/options.h"
#include "common/transform.h"
#include "explore/local_obstacles.h"
#include "explore/planner.h"

namespace sarmap {
namespace explore {

struct Velocity {
  double linear_mps = 0;
  double angular_radps = 0;
  std::string source;  // "reactive", "planner", "safety", "recovery", "look", "teleop", "stop"
};

struct ReactiveOptions {
  double danger_distance_m = 0.6;
  double unknown_rate_limit = 0.15;
  double low_average_m = 1.0;
  double max_range_margin_m = 1.0;  // finite readings above range_max - margin are unknown (Sales)
  double forward_speed_mps = 0.25;
  double turn_speed_radps = 0.5;
  template <class V>
  void Visit(V& v) {
    v("danger_distance_m", danger_distance_m,
      "stop and turn when the nearest valid range is below this", Positive());
    v("unknown_rate_limit", unknown_rate_limit,
      "stop and turn when this fraction of readings is unknown", InRange(0.0, 1.0));
    v("low_average_m", low_average_m,
      "when both sides' mean range is below this, turn to the side with more unknown", Positive());
    v("max_range_margin_m", max_range_margin_m,
      "finite readings above range_max minus this are unknown", NonNegative());
    v("forward_speed_mps", forward_speed_mps, "speed when the way is safe", Positive());
    v("turn_speed_radps", turn_speed_radps, "turn rate of the avoiding behaviour", Positive());
  }
};

struct ScanMetrics {
  double min_valid_m = 0;  // +inf when no valid reading
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

struct SafetyOptions {
  double stop_distance_m = 0.55;  // from the base centre: robot radius + what the camera cannot see
  double slow_distance_m = 1.2;
  double corridor_half_width_m = 0.3;
  double blind_fraction = 0.5;       // of the corridor's beams without information: blocked
  double footprint_radius_m = 0.28;  // the base's radius and a margin, for the swept check
  double sweep_horizon_s = 0.6;      // how far ahead the commanded arc is checked
  double unseen_lookahead_m = 0;     // unseen space the arc sweeps this far ahead: look first
  double max_pose_age_s = 0.5;       // an older POSE (against the SCAN's stamp): stand still
  double memory_s = 0;               // scan returns kept in the odometry frame this long (0: off)
  double memory_radius_m = 1.5;      // ... while within this distance of the base
  template <class V>
  void Visit(V& v) {
    v("stop_distance_m", stop_distance_m,
      "no forward motion when an obstacle ahead is nearer (from the base centre)", Positive());
    v("footprint_radius_m", footprint_radius_m,
      "no forward motion when the commanded arc brings the base this close to a map obstacle (a "
      "corner cut while turning)",
      Positive());
    v("sweep_horizon_s", sweep_horizon_s, "the commanded arc is checked this far ahead in time",
      NonNegative());
    v("unseen_lookahead_m", unseen_lookahead_m,
      "along this much of the commanded arc, space the base would sweep (footprint_radius_m) "
      "that the sensor has never seen, outside its view and beyond its minimum range (a corner "
      "beside a doorway), is looked at first: the robot turns to it on the spot (0: off)",
      NonNegative());
    v("max_pose_age_s", max_pose_age_s,
      "when the newest POSE is older than this against the SCAN's stamp (SLAM lags or is down), "
      "the robot stands still and the scan stays out of the explorer's map (0: no check)",
      NonNegative());
    v("memory_s", memory_s,
      "the scan's returns are kept this long in the odometry frame, so that the checks above "
      "still see an obstacle once it is beside the base or nearer than the camera's minimum "
      "range (0: no memory, the map alone)",
      NonNegative());
    v("memory_radius_m", memory_radius_m,
      "kept returns further than this from the base are dropped", Positive());
    v("slow_distance_m", slow_distance_m, "full speed only when the way ahead is clear this far");
    v("corridor_half_width_m", corridor_half_width_m, "half width of the corridor checked ahead",
      Positive());
    v("blind_fraction", blind_fraction,
      "the corridor counts as blocked when this fraction of its beams carries no information",
      InRange(0.0, 1.0));
  }
  void Validate(common::Validator& check) const {
    check.That(slow_distance_m > stop_distance_m, "slow_distance_m", "must exceed stop_distance_m");
  }
};

// Free distance ahead (m, from the base centre) in the robot's corridor, from the scan.
double ScanClearanceAhead(const Scan& scan, const SafetyOptions& options);

struct FollowerOptions {
  double lookahead_m = 0.5;
  double max_linear_mps = 0.35;
  double max_angular_radps = 0.8;
  double rotate_in_place_rad = 0.7;  // heading errors above this: turn on the spot first
  double heading_gain = 1.8;         // angular rate per radian of heading error
  template <class V>
  void Visit(V& v) {
    v("lookahead_m", lookahead_m, "pure-pursuit lookahead", Positive());
    v("max_linear_mps", max_linear_mps, "speed limit while following a path", Positive());
    v("max_angular_radps", max_angular_radps, "turn-rate limit", Positive());
    v("rotate_in_place_rad", rotate_in_place_rad,
      "turn on the spot when the heading error exceeds this", InRange(0.05, M_PI));
    v("heading_gain", heading_gain, "angular rate per radian of heading error", Positive());
  }
};

struct GoalOptions {
  double size_weight = 0.5;       // path metres one metre of frontier is worth
  double heading_weight_m = 0.6;  // path metres a half turn is worth (prefer what is ahead)
  double switch_margin_m = 1.5;   // a new goal must be this much better to replace the current
  double goal_reached_m = 0.3;
  double replan_period_s = 1.0;
  double blacklist_radius_m = 0.6;
  double blacklist_expiry_s = 120;
  double time_budget_s = 0;       // 0: explore until nothing is left
  double return_speed_mps = 0.2;  // for the time the way home needs (time budget)
  bool return_home = true;
  bool look_around = true;  // a full turn at the start
  // When nothing is left to explore: "home" (return, or finish) or "sweep" (search the explored
  // site again, the longest-unvisited reachable place first, until the time budget sends the
  // robot home: a long search, where people move and wake up).
  std::string when_explored = "home";
  double sweep_cell_m = 2.0;     // the site is remembered as visited in cells this size
  double sweep_min_age_s = 120;  // a cell visited more recently than this is not a goal
  template <class V>
  void Visit(V& v) {
    v("size_weight", size_weight, "path metres one metre of frontier is worth", NonNegative());
    v("heading_weight_m", heading_weight_m,
      "path metres a half turn away from the heading is worth", NonNegative());
    v("switch_margin_m", switch_margin_m,
      "a new frontier must score this much better to replace the current goal", NonNegative());
    v("goal_reached_m", goal_reached_m, "distance at which a goal counts as reached", Positive());
    v("replan_period_s", replan_period_s, "goals and paths are recomputed at most this often",
      Positive());
    v("blacklist_radius_m", blacklist_radius_m,
      "frontiers this close to a given-up goal are skipped", NonNegative());
    v("blacklist_expiry_s", blacklist_expiry_s, "a given-up goal may be tried again after this",
      Positive());
    v("time_budget_s", time_budget_s,
      "mission time after which the robot goes home (0: none); the way home is reserved",
      NonNegative());
    v("return_speed_mps", return_speed_mps, "average speed assumed for the way home", Positive());
    v("return_home", return_home, "go back to the start when exploration ends");
    v("look_around", look_around, "turn once on the spot at the start");
    v("when_explored", when_explored,
      "home: return (or finish) when nothing is left to explore; sweep: search the explored site "
      "again, the longest-unvisited place first, until the time budget sends the robot home",
      OneOf({"home", "sweep"}));
    v("sweep_cell_m", sweep_cell_m, "sweep: the site is remembered as visited in cells this size",
      Positive());
    v("sweep_min_age_s", sweep_min_age_s,
      "sweep: a cell visited more recently than this is not a goal", NonNegative());
  }
};

struct RecoveryOptions {
  double stuck_timeout_s = 6.0;    // no progress for this long while driving: stuck
  double progress_m = 0.2;         // progress: this far from where the robot was...
  double progress_rad = 0.6;       // ...or turned this much
  double blocked_timeout_s = 3.0;  // the safety layer has held the robot this long: stuck
  double backoff_m = 0.25;
  double backoff_speed_mps = 0.1;
  double turn_rad = 1.6;
  double turn_speed_radps = 0.6;
  int attempts_per_goal = 2;      // recoveries before a goal is given up
  double contact_window_s = 1.0;  // commanded forward this long...
  double contact_ratio = 0.3;     // ...but moved less than this share of it: an unseen obstacle
  int escape_after = 2;           // recoveries in a row with no plan out of where the robot is...
  double escape_s = 20.0;         // ...then escape (reactive, held by the map) this long
  double escape_radius_m = 1.0;   // or more than escape_after recoveries this close together...
  double escape_window_s = 60.0;  // ...within this long (0: only the rule above)
  template <class V>
  void Visit(V& v) {
    v("contact_window_s", contact_window_s,
      "window over which commanded and actual forward motion are compared", Positive());
    v("contact_ratio", contact_ratio,
      "moving less than this share of the commanded distance means an obstacle the sensors miss "
      "(glass): it is marked and avoided",
      InRange(0.0, 1.0));
    v("stuck_timeout_s", stuck_timeout_s, "no progress for this long while driving counts as stuck",
      Positive());
    v("progress_m", progress_m, "moving this far counts as progress", Positive());
    v("progress_rad", progress_rad, "turning this much counts as progress", Positive());
    v("blocked_timeout_s", blocked_timeout_s,
      "the safety layer holding the robot this long counts as stuck", Positive());
    v("backoff_m", backoff_m, "recovery: reverse this far (when the map behind is free)",
      NonNegative());
    v("backoff_speed_mps", backoff_speed_mps, "recovery: reversing speed", Positive());
    v("turn_rad", turn_rad, "recovery: turn this much towards the open side", NonNegative());
    v("turn_speed_radps", turn_speed_radps, "recovery: turn rate", Positive());
    v("attempts_per_goal", attempts_per_goal, "recoveries on one goal before it is given up",
      AtLeast(1));
    v("escape_after", escape_after,
      "after this many recoveries in a row with no plan out of the robot's place in the map "
      "(SLAM's pose wrong, or the map closed around it), escape: drive on the reactive "
      "behaviour, held by the map's obstacles unless the pose lies inside one (0: never)",
      AtLeast(0));
    v("escape_s", escape_s, "how long that escape lasts before planning again", Positive());
    v("escape_radius_m", escape_radius_m,
      "also escape after more than escape_after recoveries within this distance of each other "
      "within escape_window_s (contacts and holds repeating in one place: the map there is not "
      "where the robot is)",
      Positive());
    v("escape_window_s", escape_window_s,
      "the time over which recoveries in one place are counted (0: never escape for them)",
      NonNegative());
  }
};

struct SoundGoalOptions {
  double max_position_std_m = 1.5;  // heard people and voices placed less certainly are not goals
  double min_view_m = 0.8;          // look at them from this far...
  double max_view_m = 2.2;          // ...to this far, with a clear line of sight in the map
  double dwell_s = 4.0;             // facing them, so the camera can confirm
  double revisit_radius_m = 1.2;    // a visited place is not a goal again
  double max_detour_m = 25;         // farther (by path) heard people wait for the frontiers
  // Voices on SOUND_MAP that no one on PEOPLE_MAP explains are goals too: the sound map places a
  // caller behind cover from the bearings' parallax, which the robot gains by going near and
  // standing still while they call (DOAs heard while turning fast are dropped).
  bool voices = false;
  double seen_radius_m = 1.5;  // a voice this near a person on PEOPLE_MAP is that person
  double listen_s = 12.0;      // standing still near a voice: one call of a caller who repeats
  template <class V>
  void Visit(V& v) {
    v("max_position_std_m", max_position_std_m,
      "heard people and voices placed less certainly than this are not goals", Positive());
    v("min_view_m", min_view_m, "nearest viewing distance", Positive());
    v("max_view_m", max_view_m, "farthest viewing distance");
    v("dwell_s", dwell_s, "time spent facing a heard person so the camera can confirm",
      NonNegative());
    v("revisit_radius_m", revisit_radius_m,
      "a heard person near an already visited place is not a goal again", NonNegative());
    v("max_detour_m", max_detour_m,
      "heard people farther than this by path wait for exploration to bring the robot closer",
      Positive());
    v("voices", voices,
      "voices on SOUND_MAP (placed, classed voice) that nobody on PEOPLE_MAP explains are goals "
      "too: the robot goes near and listens, which places a caller behind cover");
    v("seen_radius_m", seen_radius_m,
      "a voice this near a person on PEOPLE_MAP (seen or heard) is that person, not a goal",
      NonNegative());
    v("listen_s", listen_s,
      "time spent standing still facing a voice, so that its next call is heard from there "
      "(instead of dwell_s)",
      NonNegative());
  }
  void Validate(common::Validator& check) const {
    check.That(max_view_m > min_view_m, "max_view_m", "must exceed min_view_m");
  }
};

struct TeleopCommand {
  double receive_time_s = 0;  // this process's clock: the dead man never trusts the sender's stamp
  bool override_active = false;
  bool emergency_stop = false;
  double linear_mps = 0, angular_radps = 0;
};

// A person heard (from PEOPLE_MAP) or a voice (from SOUND_MAP), in the map frame.
struct HeardPerson {
  int64_t id = -1;  // PEOPLE_MAP's person id, or SOUND_MAP's source id for a voice
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double position_std_m = 0;  // sqrt of the largest eigenvalue of the xy covariance
  bool seen = false;          // a person on PEOPLE_MAP who was also seen
};

struct ExploreOptions {
  std::string mode = "frontier";  // reactive | frontier | sound_guided
  double teleop_timeout_s = 0.5;  // the operator's override ends this long after their last message
  double teleop_max_linear_mps = 0.5;
  double teleop_max_angular_radps = 1.5;
  ReactiveOptions reactive;
  PlannerOptions planner;
  SafetyOptions safety;
  FollowerOptions follower;
  GoalOptions goals;
  RecoveryOptions recovery;
  SoundGoalOptions sound;
  template <class V>
  void Visit(V& v) {
    v("mode", mode,
      "reactive (Sales 2014), frontier (map-driven), sound_guided (frontier + people heard)",
      OneOf({"reactive", "frontier", "sound_guided"}));
    v("teleop_timeout_s", teleop_timeout_s,
      "operator override ends this long after the last TELEOP arrived", Positive());
    v("teleop_max_linear_mps", teleop_max_linear_mps, "operator speeds are clamped to this",
      Positive());
    v("teleop_max_angular_radps", teleop_max_angular_radps,
      "operator turn rates are clamped to this", Positive());
    v("reactive", reactive, "reactive behaviour (mode reactive)");
    v("planner", planner, "cost map and planner");
    v("safety", safety, "safety layer on the scan and the map");
    v("follower", follower, "path following");
    v("goals", goals, "goal selection and the mission");
    v("recovery", recovery, "stuck detection and recovery");
    v("sound", sound, "sound-guided goals (mode sound_guided)");
  }
};

// What the controller is doing, for EXPLORE_STATUS.
struct ExploreStatus {
  std::string state;      // look_around, exploring, seeking_sound, recovering, returning, home,
                          // finished, override
  std::string driven_by;  // the source of the last command
  std::optional<Eigen::Vector2d> goal_m;
  std::string goal_kind;  // frontier, sound, home
  std::vector<Eigen::Vector2d> path;
  int frontiers = 0;
  int blacklisted = 0;
  int recoveries = 0;
  int contacts = 0;  // obstacles found by running into them
  int looks = 0;     // turns on the spot to see space the base was about to sweep unseen
  double stuck_s = 0;
  double elapsed_s = 0;
};

class ExploreController {
 public:
  explicit ExploreController(const ExploreOptions& options);
  // An emergency stop latches: only a release (neither stop nor override) ends it. An override
  // during a stop drives the robot while it lasts, and the robot is stopped again after it.
  void OnTeleop(const TeleopCommand& command) {
    if (command.emergency_stop) emergency_stop_ = true;
    if (!command.emergency_stop && !command.override_active) emergency_stop_ = false;
    teleop_ = command;
  }
  bool emergency_stop() const { return emergency_stop_; }
  void OnMap(const Grid& grid);
  // `stamp_s` is the sensor time the pose is for (the SCAN stamp SLAM placed), on the clock of
  // Scan::stamp_s.
  void OnPose(const common::Rigid2d& map_from_base, double stamp_s);
  // Wheel (or visual) odometry, `stamp_s` on the clock of Scan::stamp_s. Without it the safety
  // layer's memory is kept in the map frame with SLAM's POSE.
  void OnOdometry(const common::Rigid2d& odom_from_base, double stamp_s);
  // PEOPLE_MAP: the people heard (goals in sound_guided mode unless also seen) and where everyone
  // on it is (a voice near one of them is that person).
  void OnPeopleMap(std::vector<HeardPerson> heard, std::vector<Eigen::Vector2d> people_m) {
    heard_ = std::move(heard);
    people_m_ = std::move(people_m);
  }
  // SOUND_MAP: the placed voices.
  void OnVoices(std::vector<HeardPerson> voices) { voices_ = std::move(voices); }
  // One command per scan. `now_s` is this process's clock (the scan's receive time live, its
  // log time offline): every duration in the controller is measured on it.
  Velocity OnScan(double now_s, const Scan& scan);

  const ExploreStatus& status() const { return status_; }
  bool finished() const { return state_ == State::kHome || state_ == State::kFinished; }
  const ExploreMap& map() const { return map_; }

 private:
  enum class State {
    kLookAround,
    kExploring,
    kSeekingSound,
    kSweeping,
    kRecovering,
    kReturning,
    kHome,
    kFinished
  };
  struct Goal {
    Eigen::Vector2d position_m;
    std::string kind;  // frontier, sound, home
    double score = 0;
    int64_t person_id = -1;
    bool voice = false;                     // person_id is a SOUND_MAP source
    std::optional<Eigen::Vector2d> face_m;  // sound goals: turn to face this on arrival
  };
  struct BlacklistEntry {
    Eigen::Vector2d position_m;
    double until_s;
  };

  Velocity Drive(double now_s, const Scan& scan);
  // While the pose lags the scan by more than max_pose_age_s: no motion, and every timer of
  // the mission (progress, contact, blocked, recovery, dwell) is held, so that waiting for SLAM
  // is neither being stuck nor a contact.
  Velocity WaitForPose(double now_s);
  void ResumeAfterPoseWait(double now_s);
  void Replan(double now_s);
  std::optional<Goal> ChooseFrontier(const CostField& field,
                                     const std::vector<Frontier>& frontiers) const;
  std::optional<Goal> ChooseSoundGoal(const CostField& field) const;
  // Sweep: the reachable place whose cell was visited longest ago (never: the mission start),
  // less the time to drive there; none younger than sweep_min_age_s.
  std::optional<Goal> ChooseSweepGoal(double now_s, const CostField& field) const;
  void MarkVisited(double now_s);
  std::pair<int, int> SweepCell(const Eigen::Vector2d& position_m) const;
  Velocity Follow(const Scan& scan);
  Velocity Safe(Velocity desired, const Scan& scan) const;
  // Whether driving (linear_mps, angular_radps) for sweep_horizon_s brings the base nearer than
  // footprint_radius_m to a remembered return, and nearer than it is now.
  bool ArcApproachesMemory(double linear_mps, double angular_radps) const;
  // The nearest cell (map frame) the base would newly sweep along the commanded arc that the
  // sensor has never seen, will not see from the arc before the base gets there, and could see
  // by turning now (beyond its minimum range).
  std::optional<Eigen::Vector2d> UnseenOnArc(const Velocity& desired, const Scan& scan) const;
  // Odometry at `stamp_s` (interpolated; the newest when the scan is newer), if any is recent.
  std::optional<common::Rigid2d> OdometryAt(double stamp_s) const;
  Velocity Recover(double now_s, const Scan& scan);
  // Recovery's phase 0 from here: back off, then turn towards the side the scan shows more open.
  void BeginBackOff(double now_s, const Scan& scan);
  // Recovery's phase 2: the reactive behaviour, held by the map where the pose is plausible.
  Velocity Escape(double now_s, const Scan& scan);
  // Commanded forward distance against the distance moved over contact_window_s: true when
  // the window has ended with the robot held by something (and a new window starts).
  bool ContactInWindow(double now_s);
  void RestartContactWindow(double now_s);
  Velocity EndRecovery(double now_s);
  void StartRecovery(double now_s, const Scan& scan, const std::string& why);
  void GiveUpGoal(double now_s);
  bool IsBlacklisted(const Eigen::Vector2d& p, double now_s) const;
  bool TimeToGoHome(double now_s, const CostField& field) const;
  static const char* StateName(State s);

  ExploreOptions options_;
  ReactiveExplorer reactive_;
  ExploreMap map_;
  std::optional<TeleopCommand> teleop_;
  bool emergency_stop_ = false;
  std::optional<common::Rigid2d> pose_;
  double pose_stamp_s_ = 0;
  // Odometry (stamp, odom_from_base), the last second of it, for the pose at a scan's stamp.
  std::deque<std::pair<double, common::Rigid2d>> odometry_;
  LocalObstacles local_obstacles_;
  bool local_frame_is_odometry_ = false;
  std::vector<Eigen::Vector2d> local_points_;  // the memory in the base frame at this scan
  std::optional<double> pose_wait_since_s_;
  int pose_waits_ = 0;
  bool pose_wait_warned_ = false;
  std::optional<Eigen::Vector2d> home_;
  std::vector<HeardPerson> heard_;
  std::vector<Eigen::Vector2d> people_m_;
  std::vector<HeardPerson> voices_;
  State state_ = State::kLookAround;
  std::optional<double> start_s_;
  double look_turned_rad_ = 0;
  std::optional<double> last_yaw_;
  std::optional<Goal> goal_;
  std::vector<Eigen::Vector2d> path_;
  double last_plan_s_ = -1e9;
  bool map_changed_ = false;
  std::vector<BlacklistEntry> blacklist_;
  std::vector<Eigen::Vector2d> visited_sound_;
  std::map<std::pair<int, int>, double>
      visited_cells_;  // sweep cell -> last time the robot was in it
  std::optional<double> dwell_until_s_;
  int frontier_count_ = 0;
  bool cleared_blacklist_once_ = false;
  bool cleared_contacts_once_ = false;
  int empty_plans_ = 0;
  // Progress and recovery.
  Eigen::Vector2d progress_xy_ = Eigen::Vector2d::Zero();
  double progress_yaw_ = 0, progress_s_ = 0;
  std::optional<double> blocked_since_s_;
  // Contact detection: commanded forward distance against the distance actually moved.
  double contact_since_s_ = 0, commanded_m_ = 0, last_scan_s_ = 0;
  std::string logged_state_ = "start";
  // Returning because no frontier was reachable (not for the time budget), and how many plans in
  // a row have reached a frontier since.
  bool returning_explored_ = false;
  int frontier_plans_returning_ = 0;
  Eigen::Vector2d contact_xy_ = Eigen::Vector2d::Zero();
  double last_linear_mps_ = 0;
  int goal_recoveries_ = 0;
  int recoveries_ = 0;
  int looks_ = 0;         // turns to look at unseen space on the arc (ExploreStatus::looks)
  bool looking_ = false;  // the last Drive turned to look
  State resume_state_ = State::kExploring;
  int recovery_phase_ = 0;  // 0 back off, 1 turn, 2 escape on the scan alone
  // The last plan found no way out of the robot's place in the map (no traversable cell near
  // it, or most of its own trail out of reach), and how many recoveries in a row started so.
  bool shut_in_ = false;
  int shut_in_recoveries_ = 0;
  int escapes_ = 0;
  std::deque<std::pair<double, Eigen::Vector2d>> recent_recoveries_;  // (time, map position)
  double recovery_phase_start_s_ = 0;
  std::optional<double> escape_until_s_;  // an escape (phase 2) lasts until then
  double recovery_turn_sign_ = 1;
  double recovery_yaw0_ = 0;
  Eigen::Vector2d recovery_xy0_ = Eigen::Vector2d::Zero();
  ExploreStatus status_;
};

}  // namespace explore
}  // namespace sarmap
