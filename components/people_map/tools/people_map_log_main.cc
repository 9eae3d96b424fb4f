// sarmap-log-people-map: replays the people map's inputs from an LCM log (PEOPLE_VISUAL, POSE,
// PEOPLE_AUDIO, SOUND_MAP, SLAM_ANCHORS, as `sarmap-mission-bench --people-log` writes them)
// through sarmap-people-map's own adapter (PeopleMapNode) on the log's clock
// (logtools::NodeReplay), as fast as the CPU allows; with SIM_TRUTH in the log it compares each
// person on the map with the true people, and traces, detection by detection, what moved the
// estimate near one true person.
//
//   sarmap-log people-map site-3-frontier-people.lcmlog
//   sarmap-log people-map site-3-frontier-people.lcmlog --trace person6
//   sarmap-log people-map LOG --truth-poses          # every detection placed with the true pose
//   sarmap-log people-map LOG --final-trail OUT/site-3-frontier-trail.csv  # SLAM's final graph
//   sarmap-log people-map LOG --set map.relative_pose_sigma_m=0
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/decode.h"
#include "common/message_conversions.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/node_replay.h"
#include "people_map/people_map.h"
#include "people_map/people_map_intake.h"
#include "people_map/people_map_node.h"
#include "sarmap/sim_truth_t.hpp"

namespace {

using sarmap::common::Utime;

struct TruePerson {
  std::string name;
  Eigen::Vector2d map_m = Eigen::Vector2d::Zero();
};

// The true robot pose (map frame) of each SIM_TRUTH, for --truth-poses and the pose error.
struct TruthTrail {
  std::map<Utime, sarmap::common::Rigid2d> map_from_base;
  // The SIM_TRUTH pose nearest in time (identity when none).
  bool At(Utime utime, sarmap::common::Rigid2d* pose) const {
    if (map_from_base.empty()) return false;
    auto it = map_from_base.lower_bound(utime);
    if (it == map_from_base.end()) it = std::prev(it);
    if (it != map_from_base.begin()) {
      auto before = std::prev(it);
      if (std::abs(before->first - utime) < std::abs(it->first - utime)) it = before;
    }
    *pose = it->second;
    return true;
  }
};

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-people-map", [&] {
    using namespace sarmap;
    common::ArgParser parser(
        "sarmap-log-people-map",
        "Replays PEOPLE_VISUAL, POSE, PEOPLE_AUDIO, SOUND_MAP and SLAM_ANCHORS from an LCM log\n"
        "through the people map (as sarmap-people-map would) and compares the result with "
        "SIM_TRUTH.");
    std::string log_path, trace;
    bool truth_poses = false;
    double match_m = 0.5;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddFlag("--trace", &trace,
                   "a true person's name: every detection placed within 1.5 m of them (where "
                   "POSE and the true pose put it, and the person it updated)");
    parser.AddSwitch("--truth-poses", &truth_poses,
                     "place every detection with the simulator's true pose instead of POSE "
                     "(SLAM_ANCHORS then ignored)");
    parser.AddFlag("--match-m", &match_m, "a map person this close to a true person is found");
    std::string final_trail;
    parser.AddFlag("--final-trail", &final_trail,
                   "the bench's OUT/<site>-<mode>-trail.csv: every POSE is moved by the correction "
                   "SLAM's final graph made at its time (SLAM_ANCHORS then ignored)");
    std::string sound_map_log;
    parser.AddFlag("--sound-map", &sound_map_log,
                   "take SOUND_MAP from this LCM log instead of the replayed log's own (e.g. "
                   "sarmap-log sound-map --write-map: a sound-map change tried on the people map)");
    common::NodeArgs node_args;
    const auto parsed = common::ParseNodeOptions<people_map::PeopleMapNodeOptions>(
        &parser, &node_args, argc, argv, "config/people_map.yaml");
    if (!parsed) return 0;
    const people_map::PeopleMapNodeOptions& options = *parsed;
    const common::RobotOptions robot = common::LoadRobot(options.robot_config);
    const common::Rigid3d base_from_camera = robot.base_from_camera.ToRigid3d();

    // First pass: the truth (people and the robot's trail in the map frame).
    std::map<std::string, TruePerson> truth;
    TruthTrail trail;
    {
      logtools::LcmLogReader log(log_path);
      bool have_start = false;
      common::Rigid2d map_from_world;
      logtools::LogEvent e;
      while (log.Next(&e)) {
        if (e.channel != "SIM_TRUTH") continue;
        sim_truth_t m;
        if (!common::DecodeMessage(e.data.data(), e.data.size(), &m)) continue;
        if (!have_start) {
          map_from_world =
              common::Rigid2d(m.start_pose[0], m.start_pose[1], m.start_pose[2]).inverse();
          have_start = true;
        }
        const common::Rigid3d world_from_base =
            common::ToRigid3d(m.robot_position_m, m.robot_orientation);
        const Eigen::Vector3d x = world_from_base.rotation() * Eigen::Vector3d::UnitX();
        trail.map_from_base[m.header.utime] =
            map_from_world *
            common::Rigid2d(world_from_base.translation().head<2>(), std::atan2(x.y(), x.x()));
        for (const auto& p : m.people) {
          truth[p.name] = {p.name,
                           map_from_world * Eigen::Vector2d(p.position_m[0], p.position_m[1])};
        }
      }
    }
    if (!trace.empty() && !truth.count(trace))
      throw std::runtime_error("no true person named " + trace + " in " + log_path);
    if (truth_poses && trail.map_from_base.empty())
      throw std::runtime_error("--truth-poses needs SIM_TRUTH in " + log_path);
    const auto nearest_truth = [&](const Eigen::Vector2d& xy, double* d) {
      std::string best;
      *d = std::numeric_limits<double>::infinity();
      for (const auto& [name, t] : truth) {
        const double e = (t.map_m - xy).norm();
        if (e < *d) {
          *d = e;
          best = name;
        }
      }
      return best;
    };

    // Final-graph corrections (final * online^-1) at the trail's samples, by mission time.
    std::map<double, common::Rigid2d> corrections;
    if (!final_trail.empty()) {
      std::ifstream csv(final_trail);
      if (!csv) throw std::runtime_error("cannot read " + final_trail);
      std::string line;
      std::getline(csv, line);
      while (std::getline(csv, line)) {
        std::vector<double> v;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
        if (v.size() < 12) throw std::runtime_error(final_trail + ": no final-graph columns");
        corrections[v[0]] =
            common::Rigid2d(v[8], v[9], v[10]) * common::Rigid2d(v[4], v[5], v[6]).inverse();
      }
    }
    // The node's adapter on the log's clock, as sarmap-people-map ran: its stamp gates, its
    // reorder queue released by its timer, its interpolation. A replay starts empty and saves
    // nothing.
    people_map::PeopleMapNodeOptions replay_options = options;
    replay_options.state_file = "";
    common::Node node("sarmap-log-people-map", logtools::ReplayNodeArgs(node_args));
    people_map::PeopleMapNode people_map_node(replay_options, &node);
    people_map::PeopleMap& map = *people_map_node.mutable_map();
    logtools::NodeReplay replay(&node);
    // Seen detections: where each landed, which person took it, and where the true pose would
    // have put it.
    std::map<int64_t, int> taken_by_person;
    std::map<int64_t, std::map<std::string, int>> near_truth_by_person;
    map.set_seen_trace([&](const people_map::SeenTrace& s) {
      common::Rigid2d truth_pose;
      double d_truth = std::numeric_limits<double>::infinity();
      const std::string who = nearest_truth(s.position_m.head<2>(), &d_truth);
      ++taken_by_person[s.person_id];
      if (d_truth <= 1.0) ++near_truth_by_person[s.person_id][who];
      if (trace.empty()) return;
      const Eigen::Vector2d t = truth.at(trace).map_m;
      if ((s.position_m.head<2>() - t).norm() > 1.5) return;
      // Where the true pose puts it.
      Eigen::Vector2d z_truth = s.position_m.head<2>();
      if (trail.At(s.utime, &truth_pose))
        z_truth =
            (common::Rigid3d::FromRigid2d(truth_pose) * base_from_camera * s.position_camera_m)
                .head<2>();
      const auto it = map.people().find(s.person_id);
      const Eigen::Vector2d now =
          it != map.people().end() ? it->second.seen_position_m.head<2>() : s.position_m.head<2>();
      std::printf(
          "  %8.2f s  det (%6.2f, %6.2f) %.2f m from %s, std %.2f m -> person %ld%s "
          "(now %.2f m from %s); true pose: %.2f m\n",
          common::UtimeToSeconds(s.utime - trail.map_from_base.begin()->first), s.position_m.x(),
          s.position_m.y(), (s.position_m.head<2>() - t).norm(), trace.c_str(),
          std::sqrt(s.covariance.topLeftCorner<2, 2>().trace() / 2), static_cast<long>(s.person_id),
          s.made_person ? " (new)" : "", (now - t).norm(), trace.c_str(), (z_truth - t).norm());
    });

    int64_t seen_msgs = 0, heard_msgs = 0, poses = 0, sound_map_msgs = 0, anchor_msgs = 0;
    // With poses replaced, SLAM's node poses would move people placed from other poses.
    const bool use_anchors = !truth_poses && corrections.empty();
    const Utime t0 = trail.map_from_base.empty() ? 0 : trail.map_from_base.begin()->first;
    // SOUND_MAP from another log: each of its events goes in before the first event of the
    // replayed log that is not earlier.
    std::unique_ptr<logtools::LcmLogReader> sound_maps;
    logtools::LogEvent next_map;
    bool have_next_map = false;
    if (!sound_map_log.empty()) {
      sound_maps = std::make_unique<logtools::LcmLogReader>(sound_map_log);
      have_next_map = sound_maps->Next(&next_map);
    }
    const auto stats = replay.Run(log_path, [&](logtools::LogEvent* e) {
      if (sound_maps) {
        while (have_next_map && next_map.timestamp_us <= e->timestamp_us) {
          if (next_map.channel == options.sound_map_channel) {
            ++sound_map_msgs;
            replay.Inject(next_map.channel, next_map.data);
          }
          have_next_map = sound_maps->Next(&next_map);
        }
        if (e->channel == options.sound_map_channel) return false;
      }
      if (e->channel == options.visual_channel) {
        ++seen_msgs;
      } else if (e->channel == options.sound_map_channel) {
        ++sound_map_msgs;
      } else if (e->channel == options.audio_channel) {
        ++heard_msgs;
      } else if (e->channel == options.anchors_channel) {
        if (!use_anchors) return false;
        ++anchor_msgs;
      } else if (e->channel == options.pose_channel) {
        ++poses;
        if (!truth_poses && corrections.empty()) return true;
        // The pose replaced: the true one, or moved by the final graph's correction.
        pose_t m;
        if (!common::DecodeMessage(e->data.data(), e->data.size(), &m)) return true;
        common::Rigid2d truth_pose;
        if (truth_poses && trail.At(m.header.utime, &truth_pose))
          common::FromRigid3d(common::Rigid3d::FromRigid2d(truth_pose), m.position_m,
                              m.orientation);
        if (!corrections.empty()) {
          auto c = corrections.lower_bound(common::UtimeToSeconds(m.header.utime - t0));
          if (c == corrections.end()) c = std::prev(c);
          const common::Rigid2d online = common::ToRigid3d(m.position_m, m.orientation).ToRigid2d();
          common::FromRigid3d(common::Rigid3d::FromRigid2d(c->second * online), m.position_m,
                              m.orientation);
        }
        e->data.resize(m.getEncodedSize());
        m.encode(e->data.data(), 0, static_cast<int>(e->data.size()));
      }
      return e->channel == options.pose_channel || e->channel == options.visual_channel ||
             e->channel == options.audio_channel || e->channel == options.sound_map_channel ||
             e->channel == options.anchors_channel;
    });
    people_map_node.Finish();
    replay.Drain();
    for (const auto& problem : stats.problems) {
      std::fprintf(stderr, "%s: damaged at byte %lld (%s); read on from the next event\n",
                   log_path.c_str(), static_cast<long long>(problem.file_offset),
                   problem.what.c_str());
    }
    const people_map::PeopleMapIntake& intake = people_map_node.intake();
    // A log of people heard only (a mission without vision) is a people-map input too.
    if (!seen_msgs && !heard_msgs && !sound_map_msgs)
      throw std::runtime_error("no " + options.visual_channel + ", " + options.audio_channel +
                               " or " + options.sound_map_channel + " in " + log_path);

    const Utime end = intake.latest_utime();
    const std::vector<people_map::Person> report = map.Report(end);
    std::printf(
        "%ld PEOPLE_VISUAL, %ld POSE%s, %ld SOUND_MAP%s, %ld SLAM_ANCHORS; %zu people on the "
        "map, %ld detections without a pose\n",
        static_cast<long>(seen_msgs), static_cast<long>(poses),
        truth_poses           ? " (true poses)"
        : corrections.empty() ? ""
                              : " (moved by the final graph)",
        static_cast<long>(sound_map_msgs), sound_maps ? (" from " + sound_map_log).c_str() : "",
        static_cast<long>(anchor_msgs), report.size(), static_cast<long>(intake.without_pose()));
    // One-to-one, closest pairs first, as the mission metrics match.
    struct Pair {
      double d;
      std::string name;
      int64_t id;
    };
    std::vector<Pair> pairs;
    for (const auto& p : report)
      for (const auto& [name, t] : truth)
        pairs.push_back({(p.position_m.head<2>() - t.map_m).norm(), name, p.id});
    std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
    std::map<std::string, std::pair<int64_t, double>> found;
    std::map<int64_t, std::string> matched;
    for (const Pair& q : pairs) {
      if (q.d > match_m || found.count(q.name) || matched.count(q.id)) continue;
      found[q.name] = {q.id, q.d};
      matched[q.id] = q.name;
    }
    for (const auto& [name, t] : truth) {
      if (found.count(name))
        std::printf("%-10s found: person %ld, %.2f m\n", name.c_str(),
                    static_cast<long>(found[name].first), found[name].second);
      else
        std::printf("%-10s missed\n", name.c_str());
    }
    int false_people = 0;
    for (const auto& p : report) {
      double d = 0;
      const std::string who = nearest_truth(p.position_m.head<2>(), &d);
      std::string near;
      for (const auto& [name, n] : near_truth_by_person[p.id])
        near += " " + name + ":" + std::to_string(n);
      std::printf(
          "person %3ld (%6.2f, %6.2f) %s %4d detections (%d placed within 1 m of:%s), "
          "%.0f-%.0f s, nearest %s %.2f m\n",
          static_cast<long>(p.id), p.position_m.x(), p.position_m.y(),
          matched.count(p.id) ? "found" : "FALSE", p.num_detections, taken_by_person[p.id],
          near.c_str(), common::UtimeToSeconds(p.first_detected_utime - t0),
          common::UtimeToSeconds(p.last_detected_utime - t0), who.c_str(), d);
      if (!matched.count(p.id)) ++false_people;
    }
    std::printf("found %zu of %zu within %.2f m, %d false\n", found.size(), truth.size(), match_m,
                false_people);
    return 0;
  });
}
