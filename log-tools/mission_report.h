#pragma once
// The mission report: what a log says was found, drawn on the map, and — when the log holds
// SIM_TRUTH — found versus truth with position errors. Built from decoded messages so it can be
// fed from a log (sarmap-log report) or tested directly.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_map_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sarmap/sound_map_t.hpp"

namespace sarmap {
namespace logtools {

struct MissionData {
  std::optional<sarmap::occupancy_grid_t> map;   // the last one
  std::vector<std::pair<double, double>> trail;  // robot x, y from POSE
  std::optional<sarmap::people_map_t> people;    // the last one
  std::optional<sarmap::sound_map_t> sources;    // the last one
  std::optional<sarmap::sim_truth_t> truth;      // the last one
  std::vector<std::pair<double, double>> truth_trail;
  // Time-matched robot positions (estimated map frame, simulator frame), for the alignment.
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> matched_positions;
  double duration_s = 0;
  int64_t messages = 0;
  std::string log_path;
};

struct TruthMatch {
  int64_t truth_id = -1;
  std::string name;
  double x_m = 0, y_m = 0;
  bool found = false;
  int64_t person_id = -1;
  std::string how;   // "seen", "seen (depth)", "heard", "seen + heard"
  double error_m = 0;
};

// The rigid 2D transform map_from_truth that best maps the simulator's robot positions onto
// the estimated ones (least squares, Kabsch): SLAM's map frame starts wherever the robot did,
// the simulator's is the world's. Identity when fewer than 3 matched positions.
struct Alignment {
  double yaw_rad = 0;
  Eigen::Vector2d translation = Eigen::Vector2d::Zero();
  int pairs = 0;
  double rms_m = 0;  // residual of the robot trail after alignment
  Eigen::Vector2d Apply(const Eigen::Vector2d& truth) const;
};
Alignment AlignTruth(const MissionData& data);

struct MissionSummary {
  Alignment alignment;
  int people_found = 0;
  int sources_mapped = 0;
  std::vector<TruthMatch> truth;        // empty without SIM_TRUTH
  int false_positives = 0;              // reported people matching no true person
  double match_radius_m = 0.5;
};

// Reads everything the report needs from an LCM log (damaged parts are skipped; `problems`
// gets a line per break).
MissionData LoadMission(const std::string& log_path, std::vector<std::string>* problems = nullptr);

// People matched to true people by ascending distance (each used once) within match_radius_m.
MissionSummary Summarise(const MissionData& data, double match_radius_m);
std::string HowFound(int cues);

// Writes report.html, map.png and report.json into `directory` (created if needed).
void WriteReport(const MissionData& data, const MissionSummary& summary, const std::string& directory);
std::string SummaryText(const MissionData& data, const MissionSummary& summary);

}  // namespace logtools
}  // namespace sarmap
