#pragma once
// The mission report: what a log says was found, drawn on the map, and — when the log holds
// SIM_TRUTH — found versus truth with position errors and the mission metrics (coverage of the
// reachable floor, when each person was found, stuck time, came home: mission_metrics.h). Built
// from decoded messages so it can be fed from a log (sarmap-log report) or tested directly.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "common/command_auth.h"
#include "log-tools/mission_metrics.h"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sarmap/sound_map_t.hpp"

namespace sarmap {
namespace logtools {

struct MissionData {
  std::optional<sarmap::occupancy_grid_t> map;   // the last one
  std::vector<std::pair<double, double>> trail;  // robot x, y from POSE
  bool has_start = false;                        // the first POSE: x, y, yaw
  double start_x_m = 0, start_y_m = 0, start_yaw_rad = 0;
  std::optional<sarmap::people_map_t> people;  // the last one
  std::optional<sarmap::sound_map_t> sources;  // the last one
  std::optional<sarmap::sim_truth_t> truth;    // the last one
  std::vector<std::pair<double, double>> truth_trail;
  // Time-matched robot positions (estimated map frame, simulator frame), for the alignment.
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> matched_positions;
  double duration_s = 0;
  int64_t messages = 0;
  std::string log_path;
  // Fed with SIM_TRUTH, SIM_FLOOR, MAP, PEOPLE_MAP and EXPLORE_STATUS in log order.
  MissionMetrics metrics;
};

struct TruthMatch {
  int64_t truth_id = -1;
  std::string name;
  double x_m = 0, y_m = 0;
  bool found = false;
  int64_t person_id = -1;
  std::string how;   // "seen", "seen (depth)", "heard", "seen + heard"
  double error_m = 0;
  std::optional<double> found_after_s;  // since the first SIM_TRUTH (MissionMetrics)
  bool dropped = false;                 // matched in an earlier PEOPLE_MAP, not in the last
};

// The rigid 2D transform map_from_truth from the simulator's frame (the world's) to SLAM's map
// frame. The report uses the robot's start pose (SIM_TRUTH start_pose; SLAM's map frame starts
// there: mission_metrics.h), exact even when the robot does not move. AlignTruth fits the robot
// trail instead (least squares, Kabsch) and is kept as a consistency check: its residual and
// its difference from the start pose show SLAM's drift.
struct Alignment {
  // "start pose", "trail fit", "none" or "none (trail too short)" (identity)
  std::string method = "none";
  double yaw_rad = 0;
  Eigen::Vector2d translation = Eigen::Vector2d::Zero();
  int pairs = 0;     // time-matched (estimated, true) robot positions
  double rms_m = 0;  // residual of the robot trail after alignment
  Eigen::Vector2d Apply(const Eigen::Vector2d& truth) const;
};
// The trail fit; identity ("none") when fewer than 3 matched positions or when the true trail's
// RMS spread about its mean is under 0.5 m (the rotation is then undetermined).
Alignment AlignTruth(const MissionData& data);
// map_from_truth = start_pose^-1, with the trail residual under it.
Alignment AlignByStartPose(const MissionData& data);

// A person or sound source the report does not count as found: far outside the map (beyond
// kOutsideMapMarginM of the map's extent and the robot's path) or with a position standard
// deviation over kUnlocalisedStdM (an estimate that has not converged).
struct OutsideMap {
  std::string kind;  // "person" or "sound source"
  int64_t id = -1;
  double x_m = 0, y_m = 0;
  double std_m = 0;  // sqrt of the largest eigenvalue of the xy covariance
  std::string why;   // "outside the map", "unconverged (std N m)"
};
constexpr double kOutsideMapMarginM = 5.0;
constexpr double kUnlocalisedStdM = 10.0;

// The xy extent everything found must lie in: the map's cells and the robot's path, grown by
// kOutsideMapMarginM. Empty (no map, no path) accepts every position.
struct MapExtent {
  bool empty = true;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool Contains(double x, double y) const {
    return empty || (x >= x0 && x <= x1 && y >= y0 && y <= y1);
  }
};
MapExtent ExtentOf(const MissionData& data);
// Why a position with this xy covariance (row-major 3x3) is not counted as found; "" if it is.
// A simulated sound source against the sound map: the nearest placed source within the match
// radius (each used once, by ascending distance).
struct SourceTruthMatch {
  std::string name;
  std::string kind;         // sim_sound_source_t kind: voice, music, alarm, noise
  double x_m = 0, y_m = 0;  // in the estimated map frame
  bool found = false;
  int64_t source_id = -1;
  double error_m = 0;
  std::string mapped_class;  // voice, alarm, machinery, music, unknown
  bool class_right = false;  // voice-voice, alarm-alarm, noise-machinery, music-music
  bool is_person = false;
};

// The sound class names of sound_source_t::sound_class.
std::string SoundClassName(int sound_class);

std::string OutsideReason(const MapExtent& extent, const double* position_m,
                          const double* covariance_3x3, double* std_m);

struct MissionSummary {
  Alignment alignment;  // the start pose with SIM_TRUTH
  Alignment trail_fit;  // the consistency check
  MissionMetricsResult metrics;
  int people_found = 0;                 // on the map (not in outside_map)
  int sources_mapped = 0;               // on the map (not in outside_map)
  std::vector<OutsideMap> outside_map;  // listed apart, never drawn, never matched to truth
  std::vector<TruthMatch> truth;        // empty without SIM_TRUTH
  int false_positives = 0;              // reported people matching no true person
  std::vector<SourceTruthMatch> source_truth;  // empty without SIM_TRUTH
  int non_voice_people = 0;                    // mapped persons matched to a true non-voice source
  double match_radius_m = 0.5;
};

// Reads everything the report needs from an LCM log (damaged parts are skipped; `problems`
// gets a line per break). Occupancy grids on SIM_FLOOR are the floor, on any other channel the
// map. With `bus_key` (a signed bus, common/bus_auth.h), only messages signed with it count.
MissionData LoadMission(const std::string& log_path, std::vector<std::string>* problems = nullptr,
                        const MissionMetricsOptions& metrics_options = {},
                        const common::AuthKey& bus_key = {});

// People matched to true people by ascending distance (each used once) within match_radius_m.
MissionSummary Summarise(const MissionData& data, double match_radius_m);
std::string HowFound(int cues);

// Writes report.html, map.png, map.tif (RoboCup-Rescue style GeoTIFF, geotiff.h), report.json
// and, with a coverage curve, coverage.png into `directory` (created if needed).
void WriteReport(const MissionData& data, const MissionSummary& summary,
                 const std::string& directory);
std::string SummaryText(const MissionData& data, const MissionSummary& summary);

// The people and sound sources counted as found (those not in summary.outside_map).
std::vector<sarmap::mapped_person_t> PeopleOnMap(const MissionData& data,
                                                 const MissionSummary& summary);
std::vector<sarmap::sound_source_t> SourcesOnMap(const MissionData& data,
                                                 const MissionSummary& summary);

}  // namespace logtools
}  // namespace sarmap
