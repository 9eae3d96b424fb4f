// sarmap-mission-bench: autonomous missions in one process, in simulated time
// (mission_runner.h), on generated incident sites or given worlds; prints a table per site and
// mode and writes each run's explored-area curve.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/args.h"
#include "common/memory.h"
#include "common/node_main.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/mission_metrics.h"
#include "log-tools/mission_report.h"
#include "mission/mission_runner.h"
#include "sarmap/doa_source_t.hpp"
#include "sim/floor_plan.h"
#include "sim/site_generator.h"
#include "sim/world.h"

namespace {

using namespace sarmap;

// People found, scored as `sarmap-log report` scores a log (logtools::Summarise: the last
// PEOPLE_MAP against the truth moved into the map frame by the start pose, one-to-one within
// 0.5 m; false = reported people matching nobody; time to find from MissionMetrics).
class PeopleFound {
 public:
  void OnPose(double, const pose_t& m) {
    if (!data_.has_start) {
      data_.has_start = true;
      data_.start_x_m = m.position_m[0];
      data_.start_y_m = m.position_m[1];
      data_.start_yaw_rad = 2 * std::atan2(m.orientation[3], m.orientation[0]);
    }
    if (data_.trail.empty() || std::hypot(data_.trail.back().first - m.position_m[0],
                                          data_.trail.back().second - m.position_m[1]) > 0.05)
      data_.trail.emplace_back(m.position_m[0], m.position_m[1]);
  }
  void OnPeopleMap(double t_s, const people_map_t& m, logtools::MissionMetrics* metrics) {
    // Stamped with the mission's clock (its header carries the newest detection's time).
    metrics->OnPeopleMap(start_utime_ + static_cast<int64_t>(std::llround(t_s * 1e6)), m);
    data_.people = m;
  }
  void OnTruth(double t_s, const sim_truth_t& m) {
    if (!data_.truth) start_utime_ = m.header.utime - static_cast<int64_t>(std::llround(t_s * 1e6));
    data_.truth = m;
  }
  void OnMap(const occupancy_grid_t& m) { data_.map = m; }
  void OnSoundMap(const sound_map_t& m) { data_.sources = m; }
  // The summary, with the metrics fed so far.
  logtools::MissionSummary Summary(const logtools::MissionMetrics& metrics) {
    data_.metrics = metrics;
    return logtools::Summarise(data_, kMatchRadiusM);
  }
  const std::optional<people_map_t>& people() const { return data_.people; }
  // Reported people placed by sound alone (heard, never seen) who match no true person.
  int FalseHeardOnly(const logtools::MissionSummary& summary) const {
    int n = 0;
    for (const auto& p : logtools::PeopleOnMap(data_, summary)) {
      const bool seen = p.cues & (mapped_person_t::CUE_SEEN_RGBD | mapped_person_t::CUE_SEEN_DEPTH);
      const bool matched = std::any_of(
          summary.truth.begin(), summary.truth.end(),
          [&](const logtools::TruthMatch& t) { return t.found && t.person_id == p.id; });
      n += !seen && (p.cues & mapped_person_t::CUE_HEARD) && !matched;
    }
    return n;
  }
  const std::optional<sound_map_t>& sources() const { return data_.sources; }
  static constexpr double kMatchRadiusM = 0.5;

 private:
  logtools::MissionData data_;
  int64_t start_utime_ = 0;
};

// Messages of the mission as an LCM log: the sound map's inputs (and SIM_TRUTH, SOUND_MAP) for
// `sarmap-log sound-map`, the people map's inputs (and SIM_TRUTH, PEOPLE_MAP) for
// `sarmap-log people-map`. Not opened: writes nothing.
class MissionLog {
 public:
  void Open(const std::string& path) { log_ = std::make_unique<logtools::LcmLogWriter>(path); }
  template <class T>
  void Write(const std::string& channel, const T& msg) {
    if (log_) log_->Write(channel, msg, msg.header.utime);
  }

 private:
  std::unique_ptr<logtools::LcmLogWriter> log_;
};

// Feeds the mission's messages to the same metrics as `sarmap-log report`, and notes when each
// person was first in the camera's view.
class Metrics : public mission::MissionObserver {
 public:
  void OnTruth(double t_s, const sim_truth_t& m) override {
    metrics.OnTruth(m.header.utime, m);
    people_found.OnTruth(t_s, m);
    sound_log.Write("SIM_TRUTH", m);
    people_log.Write("SIM_TRUTH", m);
    for (const auto& p : m.people) {
      if (p.visible_to_camera && !in_view_s.count(p.id)) in_view_s[p.id] = t_s;
    }
    people = static_cast<int>(m.people.size());
  }
  void OnFloor(double, const occupancy_grid_t& m) override { metrics.OnFloor(m.header.utime, m); }
  void OnMap(double, const occupancy_grid_t& m) override {
    metrics.OnMap(m.header.utime, m);
    people_found.OnMap(m);
    sound_log.Write("MAP", m);
  }
  void OnExploreStatus(double, const explore_status_t& m) override {
    metrics.OnExploreStatus(m.header.utime, m);
  }
  void OnPose(double t_s, const pose_t& m) override {
    people_found.OnPose(t_s, m);
    sound_log.Write("POSE", m);
    people_log.Write("POSE", m);
  }
  void OnPeopleMap(double t_s, const people_map_t& m) override {
    people_found.OnPeopleMap(t_s, m, &metrics);
    people_log.Write("PEOPLE_MAP", m);
  }
  void OnSeen(double, const people_detections_t& m) override {
    people_log.Write("PEOPLE_VISUAL", m);
  }
  void OnSoundMap(double, const sound_map_t& m) override {
    people_found.OnSoundMap(m);
    sound_log.Write("SOUND_MAP", m);
    people_log.Write("SOUND_MAP", m);
  }
  void OnDoaMap(double, const doa_t& m) override { sound_log.Write("DOA_MAP", m); }
  void OnDoa(double, const doa_t& m) override { sound_log.Write("DOA", m); }
  void OnHeard(double, const people_detections_t& m) override {
    sound_log.Write("PEOPLE_AUDIO", m);
    people_log.Write("PEOPLE_AUDIO", m);
  }
  void OnSlamAnchors(double, const slam_anchors_t& m) override {
    sound_log.Write("SLAM_ANCHORS", m);
    people_log.Write("SLAM_ANCHORS", m);
  }
  void OnAudio(double, const audio_frame_t& m) override {
    if (with_audio) sound_log.Write("AUDIO", m);
  }
  MissionLog sound_log, people_log;
  bool with_audio = false;  // AUDIO into the sound log
  logtools::MissionMetrics metrics;
  std::map<int64_t, double> in_view_s;
  int people = 0;
  PeopleFound people_found;
};

struct Row {
  std::string site, lighting, mode;
  double reachable_m2 = 0, mapped_fraction = 0, rate_m2_per_min = 0, t90_s = -1;
  int collisions = 0;
  double closest_gap_m = 0;  // the base's closest approach to an obstacle (m)
  double longest_stuck_s = 0;
  double longest_confined_s = 0;  // within 1 m for 60 s or more (mission_metrics.h)
  bool home = false;
  double home_s = -1;
  int in_view = 0, people = 0;
  double distance_m = 0, cpu_s = 0, explore_cpu_percent = 0, simulated_s = 0;
  double trail_rms_m = 0, trail_max_m = 0;  // SLAM pose against truth, aligned by the start pose
  // Perception (found within 0.5 m, as sarmap-log report scores it).
  bool perception = false;
  int found = 0, false_people = 0;
  int hidden = 0, hidden_found = 0, false_heard = 0;  // never in view; false people by sound alone
  double median_find_s = -1, perception_cpu_s = 0;
  int64_t heard_calls = 0;
  std::string missed;  // "name (why)", ...
  std::string sound;   // the last SOUND_MAP against the simulated emitters
};

// SLAM's trail error over the mission's samples, with the truth taken into the map frame by the
// start pose as `sarmap-log report` does; writes the aligned trails to `csv_path`.
void TrailError(const mission::MissionResult& r, const common::Rigid2d& world_from_map,
                const std::string& csv_path, Row* row) {
  const common::Rigid2d map_from_world = world_from_map.inverse();
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
  std::ofstream csv(csv_path);
  csv << "time_s,truth_x_m,truth_y_m,truth_yaw_rad,slam_x_m,slam_y_m,slam_yaw_rad,error_m,"
         "final_x_m,final_y_m,final_yaw_rad,final_error_m\n";
  for (const mission::MissionSample& s : r.samples) {
    // SLAM's final graph at this time (the scan nearest in time).
    Eigen::Vector4d final_pose(s.t_s, s.slam_pose.x(), s.slam_pose.y(), s.slam_pose.z());
    const auto after =
        std::lower_bound(r.final_slam_trail.begin(), r.final_slam_trail.end(), s.t_s,
                         [](const Eigen::Vector4d& p, double t) { return p.x() < t; });
    if (after != r.final_slam_trail.end())
      final_pose = *after;
    else if (!r.final_slam_trail.empty())
      final_pose = r.final_slam_trail.back();
    pairs.emplace_back(s.slam_pose.head<2>(), s.truth_pose.head<2>());
    const common::Rigid2d truth =
        map_from_world * common::Rigid2d(s.truth_pose.x(), s.truth_pose.y(), s.truth_pose.z());
    const double error_m = (truth.translation() - s.slam_pose.head<2>()).norm();
    row->trail_max_m = std::max(row->trail_max_m, error_m);
    csv << s.t_s << "," << truth.translation().x() << "," << truth.translation().y() << ","
        << truth.yaw_rad() << "," << s.slam_pose.x() << "," << s.slam_pose.y() << ","
        << s.slam_pose.z() << "," << error_m << "," << final_pose.y() << "," << final_pose.z()
        << "," << final_pose.w() << "," << (truth.translation() - final_pose.segment<2>(1)).norm()
        << "\n";
  }
  row->trail_rms_m = logtools::TrailResidualRms(map_from_world, pairs);
}

// Why a true person is not on the final people map: never in the camera's view, on the map
// but further than the match radius from them (the nearest reported person nobody else
// matched, within 2 m), or in view but never confirmed by the detector.
std::string WhyMissed(const logtools::TruthMatch& t, const std::map<int64_t, double>& in_view_s,
                      const logtools::MissionSummary& summary,
                      const std::optional<people_map_t>& people) {
  if (t.dropped) return "dropped from the map";
  double nearest = 1e9;
  if (people) {
    for (const auto& p : people->people) {
      const bool used = std::any_of(
          summary.truth.begin(), summary.truth.end(),
          [&](const logtools::TruthMatch& o) { return o.found && o.person_id == p.id; });
      if (!used)
        nearest = std::min(nearest, std::hypot(p.position_m[0] - t.x_m, p.position_m[1] - t.y_m));
    }
  }
  char text[64];
  if (nearest <= 2.0) {
    std::snprintf(text, sizeof(text), "placed %.2f m off", nearest);
    return text;
  }
  if (!in_view_s.count(t.truth_id)) return "never in view";
  return "in view, not detected";
}

// The long-mission figures: per period, each component's share of one core over that period,
// the memory, SLAM's graph, and what is on the maps.
void PrintReports(const std::vector<mission::MissionReport>& reports, FILE* out) {
  std::fprintf(
      out,
      "  | t min | state | driven m | CPU %% all | SLAM | explore | vision | people map | "
      "sound | RSS MB | heap MB | SLAM MB | SLAM nodes (live) | submaps (live) | nodes kept "
      "for anchors alone | kept: new area / obstacles | loop closures | "
      "optimise s (period) | MAP s (period) | MAP redrawn / drawn | "
      "people | sound sources | detections without pose |\n");
  const mission::MissionReport* prev = nullptr;
  for (const mission::MissionReport& r : reports) {
    const double dt = prev ? r.t_s - prev->t_s : r.t_s;
    auto pct = [&](double now, double before) { return dt > 0 ? 100 * (now - before) / dt : 0.0; };
    std::fprintf(out,
                 "  | %.0f | %s | %.0f | %.1f | %.1f | %.2f | %.1f | %.2f | %.1f | %.0f | %.0f | "
                 "%.1f | %lld | %lld "
                 "| %lld | %lld / %lld | %lld | %.2f | %.2f | %lld / %lld | %d | %d | %lld |\n",
                 r.t_s / 60, r.state.c_str(), r.distance_m, pct(r.cpu_s, prev ? prev->cpu_s : 0),
                 pct(r.slam_cpu_s, prev ? prev->slam_cpu_s : 0),
                 pct(r.explore_cpu_s, prev ? prev->explore_cpu_s : 0),
                 pct(r.vision_cpu_s, prev ? prev->vision_cpu_s : 0),
                 pct(r.people_map_cpu_s, prev ? prev->people_map_cpu_s : 0),
                 pct(r.sound_cpu_s, prev ? prev->sound_cpu_s : 0), r.rss_mb, r.heap_mb,
                 common::Megabytes(r.slam_memory.Total()), static_cast<long long>(r.slam_nodes),
                 static_cast<long long>(r.slam_submaps), static_cast<long long>(r.slam_nodes_kept),
                 static_cast<long long>(r.slam_submaps_kept_area),
                 static_cast<long long>(r.slam_submaps_kept_obstacles),
                 static_cast<long long>(r.slam_loop_closures),
                 r.slam_optimise_s - (prev ? prev->slam_optimise_s : 0),
                 r.slam_map_s - (prev ? prev->slam_map_s : 0),
                 static_cast<long long>(r.slam_map_redraws),
                 static_cast<long long>(r.slam_map_draws), r.people_on_map, r.sound_sources,
                 static_cast<long long>(r.detections_without_pose));
    prev = &r;
  }
}

void WriteReports(const std::vector<mission::MissionReport>& reports, const std::string& path) {
  std::ofstream csv(path);
  csv << "time_s,state,distance_m,cpu_s,slam_cpu_s,explore_cpu_s,vision_cpu_s,people_map_cpu_s,"
         "sound_cpu_s,rss_mb,heap_mb,slam_mb,slam_grids_mb,slam_precomputations_mb,"
         "slam_live_nodes_mb,slam_trimmed_nodes_mb,slam_trimmed_submaps_mb,slam_graph_mb,"
         "slam_trajectory_mb,slam_nodes,"
         "slam_submaps,slam_nodes_kept,slam_submaps_kept_area,slam_submaps_kept_obstacles,"
         "slam_optimisations,"
         "slam_loop_closures,"
         "slam_optimise_s,slam_map_s,slam_map_draws,slam_map_redraws,people_on_map,sound_sources,"
         "detections_without_pose\n";
  for (const mission::MissionReport& r : reports) {
    csv << r.t_s << "," << r.state << "," << r.distance_m << "," << r.cpu_s << "," << r.slam_cpu_s
        << "," << r.explore_cpu_s << "," << r.vision_cpu_s << "," << r.people_map_cpu_s << ","
        << r.sound_cpu_s << "," << r.rss_mb << "," << r.heap_mb << ","
        << common::Megabytes(r.slam_memory.Total()) << ","
        << common::Megabytes(r.slam_memory.submap_grids) << ","
        << common::Megabytes(r.slam_memory.precomputations) << ","
        << common::Megabytes(r.slam_memory.live_nodes) << ","
        << common::Megabytes(r.slam_memory.trimmed_nodes) << ","
        << common::Megabytes(r.slam_memory.trimmed_submaps) << ","
        << common::Megabytes(r.slam_memory.graph) << ","
        << common::Megabytes(r.slam_memory.trajectory) << "," << r.slam_nodes << ","
        << r.slam_submaps << "," << r.slam_nodes_kept << "," << r.slam_submaps_kept_area << ","
        << r.slam_submaps_kept_obstacles << "," << r.slam_optimisations << ","
        << r.slam_loop_closures << "," << r.slam_optimise_s << "," << r.slam_map_s << ","
        << r.slam_map_draws << "," << r.slam_map_redraws << "," << r.people_on_map << ","
        << r.sound_sources << "," << r.detections_without_pose << "\n";
  }
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// The people figures of one run into `row`, and each true person's outcome into `csv_path`.
void AddPeople(Metrics* metrics, const std::string& csv_path, const mission::MissionResult& r,
               Row* row) {
  const logtools::MissionSummary summary = metrics->people_found.Summary(metrics->metrics);
  row->perception = true;
  row->false_people = summary.false_positives;
  row->false_heard = metrics->people_found.FalseHeardOnly(summary);
  row->perception_cpu_s = r.vision_cpu_s + r.people_map_cpu_s + r.sound_cpu_s;
  row->heard_calls = r.heard_calls;
  std::vector<double> times;
  std::ofstream csv(csv_path);
  csv << "name,found,found_after_s,error_m,how,first_in_view_s,why_missed\n";
  for (const logtools::TruthMatch& t : summary.truth) {
    const auto view = metrics->in_view_s.find(t.truth_id);
    std::string why;
    const bool hidden = !metrics->in_view_s.count(t.truth_id);
    row->hidden += hidden;
    if (t.found) {
      ++row->found;
      row->hidden_found += hidden;
      if (t.found_after_s) times.push_back(*t.found_after_s);
    } else {
      why = WhyMissed(t, metrics->in_view_s, summary, metrics->people_found.people());
      row->missed += (row->missed.empty() ? "" : ", ") + t.name + " (" + why + ")";
    }
    csv << t.name << "," << (t.found ? 1 : 0) << ","
        << (t.found_after_s ? std::to_string(*t.found_after_s) : "") << ","
        << (t.found ? std::to_string(t.error_m) : "") << "," << t.how << ","
        << (view != metrics->in_view_s.end() ? std::to_string(view->second) : "") << "," << why
        << "\n";
  }
  // The sound map: sources, those with a position, voices among them, persons; the simulated
  // emitters a placed source matched (as sarmap-log report matches them, within 0.5 m).
  if (const auto& sources = metrics->people_found.sources()) {
    int placed = 0, voices = 0, persons = 0, matched = 0;
    for (const auto& src : sources->sources) {
      placed += src.has_position;
      voices += src.has_position && src.sound_class == doa_source_t::SOUND_CLASS_VOICE;
      persons += src.is_person;
    }
    for (const auto& e : summary.source_truth) matched += e.found;
    char text[256];
    std::snprintf(
        text, sizeof(text),
        "%zu sources, %d placed (%d voices, %d persons); %d of %zu emitters within 0.5 m; "
        "never in view: %d of %d found; false people heard only: %d",
        sources->sources.size(), placed, voices, persons, matched, summary.source_truth.size(),
        row->hidden_found, row->hidden, row->false_heard);
    row->sound = text;
  }
  if (!times.empty()) {
    std::sort(times.begin(), times.end());
    const size_t n = times.size();
    row->median_find_s = n % 2 ? times[n / 2] : 0.5 * (times[n / 2 - 1] + times[n / 2]);
  }
}

// One row of the table (a markdown table line).
void PrintRow(const Row& r, FILE* out) {
  std::fprintf(
      out,
      "| %s | %s | %s | %.0f | %.1f %% | %.1f | %s | %d | %.0f / %.0f s | %s | %d/%d | %.0f m | "
      "%.1f %% |",
      r.site.c_str(), r.lighting.c_str(), r.mode.c_str(), r.reachable_m2, 100 * r.mapped_fraction,
      r.rate_m2_per_min,
      r.t90_s < 0 ? "-" : (std::to_string(static_cast<int>(r.t90_s)) + " s").c_str(), r.collisions,
      r.longest_stuck_s, r.longest_confined_s,
      r.home ? (std::to_string(static_cast<int>(r.home_s)) + " s").c_str() : "no", r.in_view,
      r.people, r.distance_m, r.explore_cpu_percent);
  if (r.perception) {
    std::fprintf(
        out, " %d/%d | %d | %s | %lld | %.1f %% | %.0f s |\n", r.found, r.people, r.false_people,
        r.median_find_s < 0 ? "-"
                            : (std::to_string(static_cast<int>(r.median_find_s)) + " s").c_str(),
        static_cast<long long>(r.heard_calls),
        r.simulated_s > 0 ? 100 * r.perception_cpu_s / r.simulated_s : 0.0, r.cpu_s);
  } else {
    std::fprintf(out, " - | - | - | - | - | %.0f s |\n", r.cpu_s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-mission-bench", [&]() -> int {
    mission::MissionRunOptions run;
    std::string worlds, modes = "frontier,reactive", out_dir = "out/mission-bench",
                        site_config = "config/site.yaml";
    int sites = 0, first_site = 1;
    bool no_perception = false, no_sound = false, sound_log = false, audio_log = false,
         people_log = false;
    common::ArgParser parser(
        "sarmap-mission-bench",
        "Autonomous missions in simulated time: the simulator, depth-to-scan, SLAM and the "
        "explorer\n"
        "in one process, as fast as the CPU allows, on generated incident sites (sarmap-site) or "
        "given\n"
        "worlds. For each site and exploration mode it prints the share of the reachable floor "
        "mapped,\n"
        "the coverage rate against the physical bound, collisions, the longest time without "
        "progress\n"
        "and going nowhere (within 1 m for 60 s or more),\n"
        "whether the robot came home, and when each person was first in the camera's view; each "
        "run's\n"
        "explored-area curve goes to OUT/<site>-<mode>.csv, the explorer's final grid to\n"
        "OUT/<site>-<mode>-explorer.pgm, SLAM's trail against the truth (aligned by the start\n"
        "pose, as sarmap-log report does) to OUT/<site>-<mode>-trail.csv. People are found by\n"
        "sarmap-vision-people's detector and sarmap-people-map (same libraries and files) on\n"
        "SLAM's poses, and scored as sarmap-log report scores them (within 0.5 m); each person's\n"
        "outcome goes to OUT/<site>-<mode>-people.csv. The sound chain "
        "(sarmap-sound-localisation,\n"
        "sarmap-speech, sarmap-sound-map) runs on the simulator's audio and puts the people heard\n"
        "on the people map and before the explorer (mode sound_guided).");
    parser.AddFlag("--sites", &sites, "generated sites: this many seeds, from --first-site");
    parser.AddFlag("--first-site", &first_site, "first seed of the generated sites");
    parser.AddFlag("--site-config", &site_config, "generator options for the sites");
    parser.AddFlag("--worlds", &worlds,
                   "comma-separated world files (instead of or besides the sites)");
    parser.AddFlag("--modes", &modes,
                   "comma-separated exploration modes: frontier, reactive, sound_guided");
    parser.AddFlag("--duration", &run.duration_s, "simulated seconds per mission");
    parser.AddFlag("--camera-rate", &run.camera_rate_hz, "depth frames per simulated second");
    parser.AddFlag("--out", &out_dir, "folder for the generated worlds and the curves");
    parser.AddRepeated("--set-explore", &run.explore_overrides,
                       "explorer option override (key=value)");
    parser.AddRepeated("--set-sim", &run.sim_overrides, "simulator option override (key=value)");
    parser.AddRepeated("--set-slam", &run.slam_overrides, "SLAM option override (key=value)");
    parser.AddRepeated("--set-depth", &run.depth_overrides,
                       "depth-to-scan option override (key=value)");
    parser.AddFlag("--report-period", &run.report_period_s,
                   "long missions: every this many simulated seconds, each component's CPU, the "
                   "memory, SLAM's graph and optimisation time, the people and sound sources on "
                   "the maps (printed, and OUT/<site>-<mode>-long.csv); 0: off");
    parser.AddSwitch("--no-perception", &no_perception,
                     "exploration only: no people detection, no people map");
    parser.AddSwitch(
        "--no-sound", &no_sound,
        "people by sight only: no simulated audio, sound localisation, keywords or sound map");
    parser.AddSwitch("--sound-log", &sound_log,
                     "write the sound map's inputs (and the every-bin DOA), SIM_TRUTH and "
                     "SOUND_MAP to OUT/<site>-<mode>-sound.lcmlog (for sarmap-log sound-map)");
    parser.AddSwitch("--audio-log", &audio_log,
                     "with --sound-log: the simulated AUDIO too (about 0.13 MB per second), so "
                     "that sarmap-log sound-map --relocalise runs the localiser again");
    parser.AddSwitch("--people-log", &people_log,
                     "write the people map's inputs (PEOPLE_VISUAL, POSE, PEOPLE_AUDIO, SOUND_MAP, "
                     "SLAM_ANCHORS), SIM_TRUTH and PEOPLE_MAP to OUT/<site>-<mode>-people.lcmlog "
                     "(for sarmap-log people-map)");
    if (!parser.Parse(argc, argv)) return 0;
    if (sites <= 0 && worlds.empty())
      throw common::ArgError("give --sites N or --worlds FILE[,FILE...]");
    run.perception = !no_perception;
    run.sound = !no_sound;
    ::mkdir(out_dir.c_str(), 0755);

    struct Target {
      std::string name, path, lighting;
    };
    std::vector<Target> targets;
    for (int seed = first_site; seed < first_site + sites; ++seed) {
      auto site =
          common::LoadOptions<sim::SiteOptions>(site_config, {"seed=" + std::to_string(seed)});
      const sim::World world = sim::GenerateSite(site);
      const std::string path = out_dir + "/site-" + std::to_string(seed) + ".yaml";
      std::ofstream(path) << sim::SiteHeader(site) << sim::WorldToYaml(world);
      targets.push_back({"site-" + std::to_string(seed), path, world.lights_on ? "lit" : "dark"});
    }
    for (const std::string& w : Split(worlds)) {
      const sim::World world = sim::LoadWorld(w);
      targets.push_back({world.name, w, world.lights_on ? "lit" : "dark"});
    }
    // The physical bound on the coverage rate: driving straight at full speed, the depth view
    // sweeps a swath as wide as its chord at the range limit.
    const double speed = 0.35, range = 4.5, hfov = 58.0 * M_PI / 180;
    const double bound = speed * 2 * range * std::sin(hfov / 2) * 60;

    std::vector<Row> rows;
    for (const Target& target : targets) {
      for (const std::string& mode : Split(modes)) {
        mission::MissionRunOptions o = run;
        o.world = target.path;
        o.mode = mode;
        o.explorer_map_pgm = out_dir + "/" + target.name + "-" + mode + "-explorer.pgm";
        o.slam_map_pgm = out_dir + "/" + target.name + "-" + mode + "-slam.pgm";
        Metrics metrics;
        if (o.perception && o.sound && sound_log)
          metrics.sound_log.Open(out_dir + "/" + target.name + "-" + mode + "-sound.lcmlog");
        metrics.with_audio = sound_log && audio_log;
        if (o.perception && people_log)
          metrics.people_log.Open(out_dir + "/" + target.name + "-" + mode + "-people.lcmlog");
        std::fprintf(stderr, "%s %s:", target.name.c_str(), mode.c_str());
        const mission::MissionResult r = mission::RunMission(o, &metrics, [](double t) {
          if (static_cast<int>(t) % 60 == 0) std::fprintf(stderr, " %.0f", t);
        });
        std::fprintf(stderr, " s\n");
        for (const std::string& w : r.warnings) {
          std::fprintf(stderr, "  warning: simulator: %s\n", w.c_str());
        }
        if (!r.reports.empty()) {
          PrintReports(r.reports, stderr);
          WriteReports(r.reports, out_dir + "/" + target.name + "-" + mode + "-long.csv");
        }
        const logtools::MissionMetricsResult m = metrics.metrics.Result();
        Row row;
        row.site = target.name;
        row.lighting = target.lighting;
        row.mode = mode;
        row.reachable_m2 = m.reachable_m2.value_or(0);
        row.mapped_fraction = m.mapped_fraction.value_or(0);
        // Rate over the first 5 minutes (or the mission if shorter): m^2 mapped per minute.
        double at = 0, at_t = 0;
        for (const auto& p : m.coverage) {
          if (p.time_s <= 300.0 + 1e-6) {
            at = p.mapped_m2;
            at_t = p.time_s;
          }
          if (row.t90_s < 0 && p.fraction >= 0.9) row.t90_s = p.time_s;
        }
        row.rate_m2_per_min = at_t > 0 ? at / (at_t / 60) : 0;
        row.collisions = r.collisions;
        row.closest_gap_m = r.closest_gap_m;
        for (const std::string& c : r.contacts)
          std::fprintf(stderr, "  %s %s collision %s\n", target.name.c_str(), mode.c_str(),
                       c.c_str());
        row.longest_stuck_s = m.longest_stuck_s.value_or(0);
        row.longest_confined_s = m.longest_confined_s.value_or(0);
        row.home = r.came_home;
        row.home_s = r.home_after_s;
        row.in_view = static_cast<int>(metrics.in_view_s.size());
        row.people = metrics.people;
        row.distance_m = r.distance_m;
        row.cpu_s = r.cpu_s;
        row.simulated_s = r.simulated_s;
        row.explore_cpu_percent = r.simulated_s > 0 ? 100 * r.explore_cpu_s / r.simulated_s : 0;
        if (o.perception)
          AddPeople(&metrics, out_dir + "/" + target.name + "-" + mode + "-people.csv", r, &row);
        rows.push_back(row);
        PrintRow(row, stderr);  // as soon as it is known: a long batch shows its rows as it goes
        if (!row.missed.empty()) std::fprintf(stderr, "missed: %s\n", row.missed.c_str());
        if (!row.sound.empty()) std::fprintf(stderr, "sound map: %s\n", row.sound.c_str());
        std::ofstream curve(out_dir + "/" + target.name + "-" + mode + ".csv");
        curve << "time_s,mapped_m2,fraction\n";
        for (const auto& p : m.coverage)
          curve << p.time_s << "," << p.mapped_m2 << "," << p.fraction << "\n";
        Row& last = rows.back();
        const std::string trail_csv = out_dir + "/" + target.name + "-" + mode + "-trail.csv";
        TrailError(r, m.world_from_map, trail_csv, &last);
        std::fprintf(stderr,
                     "  trail RMS %.3f m, max %.2f m, mapped %.1f %%, collisions %d, closest "
                     "approach %.3f m (%s), recoveries %d, looks at unseen space %d\n",
                     last.trail_rms_m, last.trail_max_m, 100 * last.mapped_fraction,
                     last.collisions, last.closest_gap_m, r.closest_gap_what.c_str(), r.recoveries,
                     r.looks);
      }
    }

    std::printf(
        "\n| site | light | mode | reachable m^2 | mapped | m^2/min (first 5 min) | 90 %% after | "
        "collisions | "
        "longest stuck / going nowhere | home | people in view | driven | explorer CPU | found "
        "(0.5 m) | false | "
        "median time to find | heard calls | perception CPU | mission CPU |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows) PrintRow(r, stdout);
    for (const Row& r : rows) {
      if (!r.missed.empty())
        std::printf("%s %s missed: %s\n", r.site.c_str(), r.mode.c_str(), r.missed.c_str());
    }
    std::printf(
        "\nSLAM trail against the truth (aligned by the start pose, as sarmap-log report):\n");
    std::printf(
        "| site | mode | trail RMS | trail max | mapped | collisions | closest approach "
        "|\n|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows) {
      std::printf("| %s | %s | %.3f m | %.2f m | %.1f %% | %d | %.2f m |\n", r.site.c_str(),
                  r.mode.c_str(), r.trail_rms_m, r.trail_max_m, 100 * r.mapped_fraction,
                  r.collisions, r.closest_gap_m);
    }
    std::printf(
        "\ncoverage-rate bound: %.0f m^2/min (%.2f m/s x %.1f m, the depth view's width at %.1f "
        "m)\n",
        bound, speed, 2 * range * std::sin(hfov / 2), range);
    for (const std::string& mode : Split(modes)) {
      std::vector<double> mapped;
      int home = 0, collisions = 0, everyone = 0, found = 0, people = 0, false_people = 0;
      int hidden = 0, hidden_found = 0, false_heard = 0;
      double stuck = 0, confined = 0;
      for (const Row& r : rows) {
        if (r.mode != mode) continue;
        everyone += r.perception && r.found == r.people;
        found += r.found;
        people += r.people;
        false_people += r.false_people;
        hidden += r.hidden;
        hidden_found += r.hidden_found;
        false_heard += r.false_heard;
        mapped.push_back(r.mapped_fraction);
        home += r.home;
        collisions += r.collisions;
        stuck = std::max(stuck, r.longest_stuck_s);
        confined = std::max(confined, r.longest_confined_s);
      }
      if (mapped.empty()) continue;
      std::sort(mapped.begin(), mapped.end());
      const double median = mapped.size() % 2
                                ? mapped[mapped.size() / 2]
                                : 0.5 * (mapped[mapped.size() / 2 - 1] + mapped[mapped.size() / 2]);
      std::printf(
          "%s: median mapped %.1f %% over %zu runs, home %d, collisions %d, longest stuck %.0f s, "
          "longest going nowhere %.0f s",
          mode.c_str(), 100 * median, mapped.size(), home, collisions, stuck, confined);
      if (run.perception)
        std::printf(
            "; everyone found on %d of %zu, %d of %d people, %d false; never in view: %d of %d "
            "found; false people heard only: %d",
            everyone, mapped.size(), found, people, false_people, hidden_found, hidden,
            false_heard);
      std::printf("\n");
    }
    return 0;
  });
}
