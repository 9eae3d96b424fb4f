// sarmap-log-sound-map: replays the sound map's inputs from an LCM log (POSE, DOA,
// SLAM_ANCHORS, PEOPLE_AUDIO) through the same OnlineSoundMap as sarmap-sound-map, in message
// time order, deterministically and as fast as the CPU allows; prints the final map and, when
// the log holds SIM_TRUTH, each true source's error against its nearest mapped source.
//
//   sarmap-log sound-map demo.lcmlog
//   sarmap-log sound-map demo.lcmlog --no-anchors            # from POSE alone
//   sarmap-log sound-map demo.lcmlog --set map.birth_min_observations=5
//   sarmap-log sound-map demo.lcmlog --truth-poses --doa-check --doa-trace carol_voice
//   # re-run the localiser over the log's AUDIO (e.g. to try localiser options offline):
//   sarmap-log sound-map demo.lcmlog --relocalise config/sound_localisation.yaml --loc-set
//   onset_rise_db=0
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <vector>

#include "common/args.h"
#include "common/decode.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sound_localisation/localiser.h"
#include "sound_localisation/source_class.h"
#include "sound_map/joint_optimizer.h"
#include "sound_map/sound_map_messages.h"

namespace {

// Inputs stamped further behind their stream's clock are dropped by the replay (a keyword is
// published a few seconds after it was heard; nothing of the stack comes later).
constexpr double kReplayMaxBehindS = 10.0;

using sarmap::sound_map::OnlineSoundMap;
using sarmap::sound_map::Pose2;

template <class T>
bool Decode(const lcm::LogEvent& e, T* msg) {
  return e.datalen >= 0 &&
         sarmap::common::DecodeMessage(e.data, static_cast<size_t>(e.datalen), msg);
}

}  // namespace

namespace {
const char* ClassName(int c) {
  return sarmap::sound::SoundClassName(static_cast<sarmap::sound::SoundClass>(c));
}
}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-sound-map", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log-sound-map",
        "Replays POSE, DOA, SLAM_ANCHORS and PEOPLE_AUDIO from an LCM log through the sound map\n"
        "(as sarmap-sound-map would, in message time order) and compares the result with SIM_TRUTH.");
    sarmap::common::NodeArgs node_args;
    std::string log_path, truth_channel = "SIM_TRUTH", doa_trace;
    bool no_anchors = false, doa_check = false, truth_poses_in = false, heard_check = false;
    double report_every_s = 0;
    std::string relocalise_config;
    std::vector<std::string> relocalise_overrides;
    std::string relocalise_array = "config/arrays/respeaker4.yaml";
    std::string relocalise_section = "map_localiser";
    double doa_shift_s = 0;
    bool pose_check = false, joint = false;
    double joint_pose_freedom = 1.0;
    std::string trajectory_path;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddSwitch("--no-anchors", &no_anchors, "ignore SLAM_ANCHORS (POSE alone: the robot's motion)");
    parser.AddSwitch("--heard-check", &heard_check,
                     "print every heard keyword direction (PEOPLE_AUDIO) against the true bearings, and the source it marks");
    parser.AddSwitch("--doa-check", &doa_check, "compare every DOA with the true bearings of the SIM_TRUTH sources");
    parser.AddSwitch("--truth-poses", &truth_poses_in,
                     "diagnosis: SIM_TRUTH robot poses instead of POSE and SLAM_ANCHORS (map = world frame)");
    parser.AddFlag("--doa-trace", &doa_trace, "with --doa-check: print every DOA nearest this true source");
    parser.AddFlag("--truth-channel", &truth_channel, "simulator ground truth channel");
    parser.AddFlag("--relocalise", &relocalise_config,
                   "re-run sarmap-sound-localisation (this config file) over the log's AUDIO instead of its DOA");
    parser.AddFlag("--loc-section", &relocalise_section,
                   "with --relocalise: the localiser section of that file (map_localiser: the sound map's stream)");
    parser.AddFlag("--array", &relocalise_array, "with --relocalise: the microphone array file");
    parser.AddRepeated("--loc-set", &relocalise_overrides, "with --relocalise: override a localiser option (k=v)");
    parser.AddFlag("--doa-shift", &doa_shift_s,
                   "diagnosis: add this many seconds to every DOA time (does the map improve with a timing fix?)");
    parser.AddSwitch("--pose-check", &pose_check,
                     "print POSE against SIM_TRUTH along the path (every 3 s) and its RMS against a time lag");
    parser.AddFlag("--trajectory", &trajectory_path,
                   "diagnosis: poses from this file (t x y yaw per line, sarmap-slam-offline --output on the "
                   "same log) instead of POSE, SLAM_ANCHORS ignored: try SLAM settings offline");
    parser.AddSwitch("--joint", &joint,
                     "also solve the joint optimisation (§4.2) of the trajectory (POSE, or the truth with "
                     "--truth-poses) and the final map's sources from every DOA, and score it");
    parser.AddFlag("--joint-pose-freedom", &joint_pose_freedom,
                   "with --joint: multiplies the trajectory's relative-pose sigmas (larger lets the sound bend it)");
    bool trace_doas = false, trace_anchors = false;
    double anchor_covariance_scale = 1.0;
    parser.AddSwitch("--trace-doas", &trace_doas,
                     "diagnosis: after every DOA, print each source and the current pose with its variance");
    parser.AddSwitch("--trace-anchors", &trace_anchors,
                     "diagnosis: print every SLAM_ANCHORS against the map's anchors, and the sources before and after it");
    parser.AddFlag("--anchor-covariance-scale", &anchor_covariance_scale,
                   "diagnosis: multiply SLAM_ANCHORS' covariance by this (with use_slam_covariance)");
    bool trace_evidence = false;
    parser.AddSwitch("--trace-evidence", &trace_evidence,
                     "diagnosis: at the end, print every source where the bearings cross (map.evidence) with its "
                     "support and the nearest true source");
    parser.AddFlag("--report-every", &report_every_s, "also print the errors every this many seconds (0: end only)");
    const auto parsed = sarmap::common::ParseNodeOptions<sarmap::sound_map::SoundMapNodeOptions>(
        &parser, &node_args, argc, argv, "config/sound_map.yaml");
    if (!parsed) return 0;
    const auto& options = *parsed;
    const auto robot = sarmap::common::LoadRobot(options.robot_config);
    OnlineSoundMap map(options.map, sarmap::sound_map::MountFromRobot(robot));

    lcm::LogFile log(log_path, "r");
    if (!log.good()) throw std::runtime_error("cannot read log " + log_path);
    // Inputs keyed by message time (stable: log order breaks ties), as the node's queue does.
    std::multimap<int64_t, std::function<void()>> inputs;
    sarmap::sim_truth_t truth;
    bool have_truth = false;
    // The SLAM map frame starts at the robot's first pose; the truth is in the world frame.
    // world_from_map = truth pose ∘ POSE^-1 at the first POSE (nearest truth message).
    std::map<int64_t, Pose2> truth_poses;  // world_from_base by utime
    std::map<int64_t, Pose2> slam_poses;   // map_from_base by utime
    std::map<int64_t, int64_t> node_utime;  // SLAM node id -> first POSE time naming it
    std::vector<std::pair<int64_t, std::vector<std::pair<int64_t, Pose2>>>> anchor_log;
    std::vector<std::pair<int64_t, sarmap::doa_t>> doa_log;
    sarmap::sound_map_t live;  // the last SOUND_MAP the running node published, if logged
    int64_t live_msgs = 0;
    int64_t doa_msgs = 0, doa_sources = 0, max_track = -1, first_utime = -1;
    std::map<int, int64_t> kinds;
    std::map<int64_t, std::vector<char>> truth_active;  // SIM_TRUTH time -> each source sounding
    // --relocalise: the localiser over the logged AUDIO, as the node runs it.
    std::unique_ptr<sarmap::sound::Localiser> localiser;
    std::unique_ptr<sarmap::sound::DirectionalClassifier> classifier;  // the file's `classes`
    sarmap::sound::ArrayGeometry geometry;
    sarmap::sound::LocaliserOptions loc_options;
    if (!relocalise_config.empty()) {
      const std::string path = sarmap::common::ResolveConfigPath(relocalise_config);
      std::vector<std::string> loc_over;
      for (const auto& o : relocalise_overrides) loc_over.push_back(o);
      loc_options = sarmap::common::LoadOptions<sarmap::sound::LocaliserOptions>(path, loc_over, relocalise_section);
      const auto array_path = sarmap::common::ResolveConfigPath(relocalise_array);
      const auto array = sarmap::common::LoadMicArray(array_path);
      geometry = sarmap::sound::ArrayGeometry::FromOptions(array);
      localiser = std::make_unique<sarmap::sound::Localiser>(
          geometry, loc_options,
          sarmap::sound::SensorModel::FromArray(array, array_path.substr(0, array_path.find_last_of('/') + 1)));
      // The file's `classes` section, as the node classifies each direction (none: unclassified).
      try {
        classifier = std::make_unique<sarmap::sound::DirectionalClassifier>(
            geometry, localiser->kind(),
            sarmap::common::LoadOptions<sarmap::sound::SourceClassOptions>(path, {}, "classes"));
      } catch (const sarmap::common::OptionsError& e) {
        printf("no source classes: %s\n", e.what());
      }
    }
    int64_t expected_index = -1;
    // --heard-check: each heard keyword direction against the truth, and the source it marks.
    std::function<void(int64_t, const OnlineSoundMap::Doa&, const std::string&, int64_t)> on_heard_check;
    double localiser_cpu_s = 0;  // --relocalise: the localiser's own CPU time
    double classifier_cpu_s = 0;  // --relocalise: the source classifier's
    std::vector<sarmap::sound::LocaliserOutput> outs;
    const int64_t doa_shift_us = static_cast<int64_t>(std::llround(doa_shift_s * 1e6));
    auto on_doa = [&](const sarmap::doa_t& m) {
      ++doa_msgs;
      doa_log.emplace_back(m.header.utime, m);
      for (const auto& s : m.sources) {
        ++doa_sources;
        ++kinds[s.kind];
        max_track = std::max(max_track, s.track_id);
      }
      const auto doas = sarmap::sound_map::DoasFromMessage(m);
      const std::string device = m.device_id;
      const int64_t t = m.header.utime + doa_shift_us;
      inputs.emplace(t, [&map, t, device, doas, trace_doas] {
        map.OnDoa(t, device, doas);
        if (trace_doas)
          for (const auto& s : map.Sources(t))
            printf("DOA t=%.2f source %ld (%.3f %.3f) cur (%.3f %.3f %.2f) ccov %.2e %.2e\n", t * 1e-6, static_cast<long>(s.id), s.position_m.x(), s.position_m.y(),
                   map.ekf().current().x, map.ekf().current().y, map.ekf().current().yaw * 180 / M_PI,
                   map.ekf().current_covariance()(0, 0), map.ekf().current_covariance()(2, 2));
      });
    };

    const bool poses_from_file = !trajectory_path.empty();
    if (poses_from_file) {
      if (truth_poses_in) throw std::runtime_error("--trajectory and --truth-poses exclude each other");
      no_anchors = true;
      std::ifstream in(trajectory_path);
      if (!in) throw std::runtime_error("cannot read trajectory " + trajectory_path);
      // What sarmap-slam adds to a node's covariance for the local match (pose_sigma_*).
      const Eigen::Matrix3d cov = Eigen::Vector3d(0.02 * 0.02, 0.02 * 0.02, std::pow(M_PI / 180, 2)).asDiagonal();
      for (std::string line; std::getline(in, line);) {
        double ts, x, y, yaw;
        if (line.empty() || line[0] == '#' || std::sscanf(line.c_str(), "%lf %lf %lf %lf", &ts, &x, &y, &yaw) != 4) continue;
        const int64_t t = std::llround(ts * 1e6);
        const Pose2 pose(x, y, yaw);
        slam_poses[t] = pose;
        inputs.emplace(t, [&map, t, pose, cov] { map.OnPose(t, pose, cov, -1); });
      }
      if (slam_poses.empty()) throw std::runtime_error("no poses in " + trajectory_path);
    }
    // Each input stream gated on its own clock, on the log's receive times, as the node gates
    // it live: a far-future stamp (a skewed or forged message the recorder heard) is dropped.
    // The replay orders the whole log by stamp, so a stamp far behind would be applied first
    // (the node's queue drops it as late): those are dropped too.
    sarmap::common::StampGateOptions gate_options = options.stamp_gate;
    if (gate_options.max_behind_s <= 0) gate_options.max_behind_s = kReplayMaxBehindS;
    sarmap::common::StampGates gates(gate_options);
    const std::vector<std::string> gated = {options.pose_channel, options.doa_channel, "AUDIO",
                                            options.anchors_channel, options.people_audio_channel};
    for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
      const int stream =
          static_cast<int>(std::find(gated.begin(), gated.end(), e->channel) - gated.begin());
      sarmap::common::Utime stamp;
      if (stream < static_cast<int>(gated.size()) &&
          sarmap::common::EncodedHeaderUtime(e->data, e->datalen, &stamp) &&
          !gates.Accept(stream, stamp, 1e-6 * static_cast<double>(e->timestamp)))
        continue;
      if (e->channel == options.pose_channel && !truth_poses_in && !poses_from_file) {
        sarmap::pose_t m;
        if (!Decode(*e, &m)) continue;
        const Pose2 pose = sarmap::sound_map::PlanarPose(m);
        const Eigen::Matrix3d cov = sarmap::common::PlanarCovariance(m.covariance);
        const int64_t t = m.header.utime, node = m.node_id;
        if (node >= 0 && !node_utime.count(node)) node_utime[node] = t;
        slam_poses[t] = pose;
        inputs.emplace(t, [&map, t, pose, cov, node] { map.OnPose(t, pose, cov, node); });
      } else if (e->channel == options.doa_channel && !localiser) {
        sarmap::doa_t m;
        if (!Decode(*e, &m)) continue;
        on_doa(m);
      } else if (e->channel == "AUDIO" && localiser) {
        sarmap::audio_frame_t a;
        if (!Decode(*e, &a) || a.sample_format != sarmap::audio_frame_t::SAMPLE_INT16) continue;
        if (expected_index >= 0 && a.first_sample_index != expected_index) {
          localiser->ResetStream();
          if (classifier) classifier->ResetStream();
        }
        expected_index = a.first_sample_index + a.num_samples;
        const int64_t before = localiser->samples_seen();
        outs.clear();
        const std::clock_t cpu0 = std::clock();
        localiser->Push(a.samples.data(), a.num_samples, a.num_channels, &outs);
        localiser_cpu_s += static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
        if (classifier) {
          const std::clock_t c0 = std::clock();
          classifier->Push(a.samples.data(), a.num_samples, a.num_channels);
          classifier_cpu_s += static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
        }
        for (const auto& o : outs) {  // as sarmap-sound-localisation publishes them
          sarmap::doa_t d;
          d.header.utime = a.header.utime + static_cast<int64_t>(std::llround(
                                                static_cast<double>(o.centre_sample - before) / geometry.sample_rate_hz * 1e6));
          d.device_id = a.device_id;
          auto add = [&](int64_t id, const sarmap::sound::Direction& dir,
                         const Eigen::Matrix2d& cov) {
            sarmap::doa_source_t s{};
            s.track_id = id;
            s.kind = static_cast<int8_t>(localiser->kind());
            s.azimuth_rad = dir.azimuth_rad;
            s.elevation_rad = dir.elevation_rad;
            for (int i = 0; i < 4; ++i) s.covariance[i] = cov(i / 2, i % 2);
            d.sources.push_back(s);
          };
          for (const auto& t : o.tracks)
            if (t.updated) add(t.id, t.direction, t.covariance);
          for (const auto& dir : o.directions) {
            bool in_track = false;
            for (const auto& t : o.tracks)
              in_track |= t.updated && sarmap::sound::AngularDistanceRad(geometry, localiser->kind(), t.direction,
                                                                          dir.direction) <
                                           sarmap::sound::DegToRad(loc_options.tracker.gate_deg);
            if (!in_track) add(-1, dir.direction, dir.covariance);
          }
          d.num_sources = static_cast<int32_t>(d.sources.size());
          if (classifier && !d.sources.empty()) {
            std::vector<sarmap::sound::Direction> dirs;
            for (const auto& s : d.sources) dirs.push_back({s.azimuth_rad, s.elevation_rad});
            const int64_t block =
                static_cast<int64_t>(std::llround(loc_options.block_s * geometry.sample_rate_hz));
            const std::clock_t c0 = std::clock();
            const auto classes = classifier->Observe(o.end_sample - block, o.end_sample, dirs);
            classifier_cpu_s += static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
            for (size_t i = 0; i < classes.size(); ++i) {
              d.sources[i].sound_class = static_cast<int8_t>(classes[i].sound_class);
              d.sources[i].class_confidence = static_cast<float>(classes[i].confidence);
            }
          }
          on_doa(d);
        }
      } else if (e->channel == options.anchors_channel && !no_anchors && !truth_poses_in) {
        sarmap::slam_anchors_t m;
        if (!Decode(*e, &m)) continue;
        Pose2 current;
        std::vector<std::pair<int64_t, Pose2>> anchors;
        Eigen::MatrixXd cov;
        if (!sarmap::sound_map::AnchorsFromMessage(m, &current, &anchors, &cov)) continue;
        const int64_t t = m.header.utime;
        anchor_log.emplace_back(t, anchors);
        const bool loop_closed = m.loop_closed;
        inputs.emplace(t, [&map, t, current, anchors, cov, loop_closed, trace_anchors,
                           anchor_covariance_scale] {
          const bool debug = trace_anchors;
          if (debug) {
            printf("ANCHORS t=%.2f current (%.3f %.3f %.2f) ekf current (%.3f %.3f %.2f) cov diag", t * 1e-6, current.x, current.y, current.yaw * 180 / M_PI, map.ekf().current().x, map.ekf().current().y, map.ekf().current().yaw * 180 / M_PI);
            for (int i = 0; i < std::min<int>(6, cov.rows()); ++i) printf(" %.2e", cov(i, i));
            printf("\n");
            for (const auto& a : anchors) {
              printf("  node %ld (%.3f %.3f %.2f)", static_cast<long>(a.first), a.second.x, a.second.y, a.second.yaw * 180 / M_PI);
              for (int64_t e : map.ekf().anchor_ids())
                if (map.AnchorNode(e) == a.first) printf(" ekf anchor %ld (%.3f %.3f %.2f)", static_cast<long>(e), map.ekf().anchor(e).x, map.ekf().anchor(e).y, map.ekf().anchor(e).yaw * 180 / M_PI);
              printf("\n");
            }
            for (const auto& s : map.Sources(t)) printf("  before: source %ld (%.2f %.2f)\n", static_cast<long>(s.id), s.position_m.x(), s.position_m.y());
          }
          map.OnSlamAnchors(t, current, anchors, Eigen::MatrixXd(cov * anchor_covariance_scale),
                            loop_closed);
          if (debug)
            for (const auto& s : map.Sources(t)) printf("  after: source %ld (%.2f %.2f)\n", static_cast<long>(s.id), s.position_m.x(), s.position_m.y());
        });
      } else if (!options.site_map_channel.empty() && e->channel == options.site_map_channel) {
        sarmap::occupancy_grid_t m;
        Eigen::Vector2d lo, hi;
        if (!Decode(*e, &m) || !sarmap::sound_map::SiteBox(m, &lo, &hi)) continue;
        const int64_t t = m.header.utime;
        inputs.emplace(t, [&map, lo, hi] { map.SetSite(lo, hi); });
      } else if (e->channel == options.people_audio_channel) {
        sarmap::people_detections_t m;
        if (!Decode(*e, &m)) continue;
        const auto heard = sarmap::sound_map::HeardDirections(m);
        std::vector<std::string> keywords;  // HeardDirections' detections, in order
        for (const auto& d : m.detections)
          if (d.cue == sarmap::person_detection_t::CUE_HEARD && std::isfinite(d.azimuth_rad))
            keywords.push_back(d.keyword + "' conf " + std::to_string(d.confidence).substr(0, 4) + " '");
        const int64_t t = m.header.utime;
        inputs.emplace(t, [&map, &on_heard_check, t, heard, keywords] {
          for (size_t i = 0; i < heard.size(); ++i) {
            const int64_t id = map.OnHeardDirection(heard[i]);
            if (on_heard_check) on_heard_check(t, heard[i], i < keywords.size() ? keywords[i] : "", id);
          }
        });
      } else if (e->channel == options.sound_map_channel) {
        sarmap::sound_map_t m;
        if (Decode(*e, &m)) {
          live = m;
          ++live_msgs;
        }
      } else if (e->channel == truth_channel) {
        sarmap::sim_truth_t m;
        if (!Decode(*e, &m)) continue;
        truth = m;
        have_truth = true;
        std::vector<char>& active = truth_active[m.header.utime];
        for (const auto& ts : m.sources) active.push_back(ts.active);
        const Eigen::Quaterniond q(m.robot_orientation[0], m.robot_orientation[1], m.robot_orientation[2],
                                   m.robot_orientation[3]);
        const Eigen::Vector3d x = q.normalized() * Eigen::Vector3d::UnitX();
        const Pose2 tp(m.robot_position_m[0], m.robot_position_m[1], std::atan2(x.y(), x.x()));
        truth_poses[m.header.utime] = tp;
        if (truth_poses_in) {
          const int64_t t = m.header.utime;
          slam_poses[t] = tp;
          inputs.emplace(t, [&map, t, tp] { map.OnPose(t, tp, Eigen::Matrix3d::Identity() * 1e-6, -1); });
        }
      }
    }
    if (gates.dropped() > 0)
      printf("%lld inputs stamped far from their stream's clock dropped\n",
             static_cast<long long>(gates.dropped()));
    if (inputs.empty()) throw std::runtime_error("no sound map input in " + log_path);
    first_utime = inputs.begin()->first;
    // Which true sources sounded at time t (the SIM_TRUTH before it); empty: unknown.
    auto active_at = [&](int64_t t) -> std::vector<char> {
      auto it = truth_active.upper_bound(t);
      if (it == truth_active.begin()) return {};
      return std::prev(it)->second;
    };
    auto truth_at = [&](int64_t t) {
      auto it = truth_poses.lower_bound(t);
      if (it == truth_poses.end()) --it;
      return it->second;
    };
    Pose2 world_from_map;
    if (!truth_poses.empty() && !slam_poses.empty()) {
      const auto& first = *slam_poses.begin();
      world_from_map = sarmap::sound_map::Compose(truth_at(first.first), sarmap::sound_map::Between(first.second, Pose2()));
      printf("world_from_map (first POSE vs SIM_TRUTH): (%.3f, %.3f, %.2f deg)\n", world_from_map.x,
             world_from_map.y, world_from_map.yaw * 180 / M_PI);
    }
    if (!truth_poses.empty()) {
      double max_pos = 0, max_yaw = 0, sum2 = 0;
      for (const auto& [t, p] : slam_poses) {
        const Pose2 w = sarmap::sound_map::Compose(world_from_map, p);
        const Pose2 tr = truth_at(t);
        const double e = std::hypot(w.x - tr.x, w.y - tr.y);
        max_pos = std::max(max_pos, e);
        sum2 += e * e;
        max_yaw = std::max(max_yaw, std::abs(sarmap::sound_map::WrapAngle(w.yaw - tr.yaw)));
      }
      printf("POSE against SIM_TRUTH: %zu poses, RMS %.3f m, max %.3f m, max heading error %.2f deg\n",
             slam_poses.size(), std::sqrt(sum2 / std::max<size_t>(1, slam_poses.size())), max_pos,
             max_yaw * 180 / M_PI);
      if (pose_check) {
        int64_t next = slam_poses.begin()->first;
        for (const auto& [t, p] : slam_poses) {
          if (t < next) continue;
          next = t + 3000000;
          const Pose2 w = sarmap::sound_map::Compose(world_from_map, p);
          const Pose2 tr = truth_at(t);
          printf("  t %5.1f truth (%5.2f %5.2f %6.1f) err (%+.2f %+.2f %+.2f deg)\n", (t - slam_poses.begin()->first) * 1e-6,
                 tr.x, tr.y, tr.yaw * 180 / M_PI, w.x - tr.x, w.y - tr.y,
                 sarmap::sound_map::WrapAngle(w.yaw - tr.yaw) * 180 / M_PI);
        }
        for (double lag = -0.6; lag <= 0.61; lag += 0.1) {
          double s2 = 0, y2 = 0;
          for (const auto& [t, p] : slam_poses) {
            const Pose2 w = sarmap::sound_map::Compose(world_from_map, p);
            const Pose2 tr = truth_at(t + static_cast<int64_t>(lag * 1e6));
            s2 += std::pow(w.x - tr.x, 2) + std::pow(w.y - tr.y, 2);
            y2 += std::pow(sarmap::sound_map::WrapAngle(w.yaw - tr.yaw), 2);
          }
          printf("  lag %+.1f s: RMS %.3f m, heading RMS %.2f deg\n", lag, std::sqrt(s2 / slam_poses.size()),
                 std::sqrt(y2 / slam_poses.size()) * 180 / M_PI);
        }
        // The sound map's anchors (SLAM nodes) as SLAM_ANCHORS gives them, against the truth at
        // the time their node was current, every 5 s.
        int64_t next_anchor = 0;
        for (const auto& [t, anchors] : anchor_log) {
          if (t < next_anchor) continue;
          next_anchor = t + 5000000;
          for (const auto& [id, pose] : anchors) {
            auto nt = node_utime.find(id);
            if (nt == node_utime.end()) continue;
            const Pose2 w = sarmap::sound_map::Compose(world_from_map, pose);
            const Pose2 tr = truth_at(nt->second);
            printf("  anchors t %5.1f: node %ld (current at %5.1f s) err (%+.2f %+.2f m, %+.2f deg)\n",
                   (t - slam_poses.begin()->first) * 1e-6, static_cast<long>(id),
                   (nt->second - slam_poses.begin()->first) * 1e-6, w.x - tr.x, w.y - tr.y,
                   sarmap::sound_map::WrapAngle(w.yaw - tr.yaw) * 180 / M_PI);
          }
        }
      }
    }
    auto to_world = [&](const Eigen::Vector3d& p) {
      const Pose2 w = sarmap::sound_map::Compose(world_from_map, Pose2(p.x(), p.y(), 0));
      return Eigen::Vector2d(w.x, w.y);
    };
    if (heard_check && have_truth) {
      const auto mount = sarmap::sound_map::MountFromRobot(robot);
      on_heard_check = [&, mount](int64_t t, const OnlineSoundMap::Doa& d, const std::string& keyword, int64_t id) {
        const Pose2 base = truth_at(t);
        const Pose2 arr = sarmap::sound_map::Compose(base, Pose2(mount.x_m, mount.y_m, mount.yaw_rad));
        std::string nearest;
        double best = 1e9;
        for (const auto& ts : truth.sources) {
          const double b = std::atan2(ts.position_m[1] - arr.y, ts.position_m[0] - arr.x) - arr.yaw;
          const double e = sarmap::sound_map::WrapAngle(d.azimuth_rad - b) * 180 / M_PI;
          if (std::abs(e) < std::abs(best)) {
            best = e;
            nearest = ts.name;
          }
        }
        printf(
            "  heard t=%6.2f track %3ld '%s' az %7.1f: nearest true %s (%+.1f deg) -> source %ld",
            (t - first_utime) * 1e-6, static_cast<long>(d.track_id),
            sarmap::common::EscapeForLog(keyword).c_str(), d.azimuth_rad * 180 / M_PI,
            nearest.c_str(), best, static_cast<long>(id));
        for (const auto& s : map.Sources(t))
          if (s.id == id) {
            const Eigen::Vector2d w = to_world(s.position_m);
            printf(" at (%.2f, %.2f)", w.x(), w.y());
          }
        printf("\n");
      };
    }
    if (doa_check && have_truth) {
      // Each DOA's azimuth against the true bearing (truth robot pose, array mount) of the
      // nearest true source: how good are the localiser's bearings?
      const auto mount = sarmap::sound_map::MountFromRobot(robot);
      std::map<std::string, std::vector<double>> errors, signed_errors;
      std::map<std::string, std::map<int, int>> classes;  // DOAs within 10 deg of a sounding source
      std::vector<double> all;
      for (const auto& [t, m] : doa_log) {
        const Pose2 base = truth_at(t + doa_shift_us);
        const Pose2 arr = sarmap::sound_map::Compose(base, Pose2(mount.x_m, mount.y_m, mount.yaw_rad));
        const std::vector<char> active = active_at(t + doa_shift_us);
        for (const auto& s : m.sources) {
          double best = 1e9, signed_best = 0;
          std::string name;
          bool best_active = false;
          for (size_t j = 0; j < truth.sources.size(); ++j) {
            const auto& ts = truth.sources[j];
            double b = std::atan2(ts.position_m[1] - arr.y, ts.position_m[0] - arr.x) - arr.yaw;
            // Linear arrays: the angle to the array's x axis (0..pi), in the plane |bearing|.
            if (s.kind == sarmap::doa_source_t::KIND_ANGLE_1D) b = std::abs(sarmap::sound_map::WrapAngle(b));
            const double se = sarmap::sound_map::WrapAngle(s.azimuth_rad - b) * 180 / M_PI;
            const bool sounding = j < active.size() && active[j];
            // A sounding source takes precedence over a silent one a little nearer.
            if ((sounding && !best_active && std::abs(se) < 10) || ((sounding || !best_active) && std::abs(se) < best)) {
              best = std::abs(se);
              signed_best = se;
              name = ts.name;
              best_active = sounding;
            }
          }
          errors[name].push_back(best);
          if (best < 10 && best_active) ++classes[name][s.sound_class];
          if (name == doa_trace)
            printf("  trace t=%6.2f robot (%5.2f, %5.2f, %6.1f deg) track %3ld doa %7.1f true %7.1f err %6.1f sigma %.1f\n",
                   (t - doa_log.front().first) * 1e-6, base.x, base.y, base.yaw * 180 / M_PI,
                   static_cast<long>(s.track_id), s.azimuth_rad * 180 / M_PI,
                   (s.azimuth_rad * 180 / M_PI) - signed_best, signed_best, std::sqrt(s.covariance[0]) * 180 / M_PI);
          if (best < 25) signed_errors[name].push_back(signed_best);
          all.push_back(best);
        }
      }
      auto median = [](std::vector<double> v) {
        if (v.empty()) return std::nan("");
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        return v[v.size() / 2];
      };
      int within10 = 0;
      for (double e : all) within10 += e < 10;
      printf("DOA check: %zu DOAs, %d within 10 deg of a true source, median error %.1f deg\n", all.size(), within10,
             median(all));
      for (const auto& [name, v] : errors) {
        printf("  nearest %-18s %4zu DOAs, median %.1f deg; within 25 deg: signed median %.1f deg; classes within 10 deg "
               "while it sounded:",
               name.c_str(), v.size(), median(v), median(signed_errors[name]));
        for (const auto& [c, n] : classes[name]) printf(" %s %d", ClassName(c), n);
        printf("\n");
      }
    }

    auto report = [&](int64_t now, bool final_report) {
      const auto sources = map.Sources(now);
      int converged = 0;
      for (const auto& s : sources) converged += s.state == OnlineSoundMap::Source::kConverged;
      const auto& c = map.counters();
      printf("t=%6.1f s: %zu sources (%d converged), born %ld, pruned %ld (+%ld mirrors), DOAs used %ld, "
             "tentative %ld, gated out %ld, dropped while turning %ld, too steep %ld, "
             "on the robot's path %ld\n",
             (now - first_utime) * 1e-6, sources.size(), converged, static_cast<long>(c.doa_new_sources),
             static_cast<long>(c.sources_pruned), static_cast<long>(c.mirrors_pruned),
             static_cast<long>(c.doa_used), static_cast<long>(c.doa_tentative), static_cast<long>(c.doa_gated_out),
             static_cast<long>(c.doa_while_turning), static_cast<long>(c.doa_too_steep),
             static_cast<long>(c.sources_on_path));
      if (final_report) {
        for (const auto& s : sources) {
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s.covariance.topLeftCorner<2, 2>());
          const Eigen::Vector2d w = to_world(s.position_m);
          printf(
              "  source %3ld at (%6.2f, %6.2f, %5.2f) m (world %6.2f, %6.2f), std %.2f m, %s, %d "
              "DOAs, %s %.0f%%%s%s\n",
              static_cast<long>(s.id), s.position_m.x(), s.position_m.y(), s.position_m.z(), w.x(),
              w.y(), std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff())),
              s.state == OnlineSoundMap::Source::kConverged ? "converged"
              : s.state == OnlineSoundMap::Source::kSilent  ? "silent"
                                                            : "initialising",
              s.num_observations, ClassName(s.sound_class), 100 * s.class_confidence,
              s.has_position ? "" : ", bearing only (position = where heard from)",
              s.is_person ? ", person" : "");
        }
      }
      if (final_report && trace_evidence) {
        printf("  where the bearings cross (%zu rays kept, %ld solves):\n", map.evidence_rays(),
               static_cast<long>(c.evidence_solves));
        for (const auto& e : map.evidence_sources()) {
          const Eigen::Vector2d w = to_world(Eigen::Vector3d(e.position_m.x(), e.position_m.y(), 0));
          std::string nearest = "-";
          double nearest_m = std::numeric_limits<double>::infinity();
          for (const auto& ts : truth.sources) {
            const double d = (w - Eigen::Vector2d(ts.position_m[0], ts.position_m[1])).norm();
            if (d < nearest_m) nearest_m = d, nearest = ts.name;
          }
          printf("    (%6.2f, %6.2f) world (%6.2f, %6.2f): %5.1f rays, %3.0f strong, std %.2f m, parallax %3.0f deg, "
                 "votes v%.0f a%.0f m%.0f u%.0f%s%s; nearest true %s %.2f m\n",
                 e.position_m.x(), e.position_m.y(), w.x(), w.y(), e.rays, e.strong_rays, e.largest_sigma_m,
                 e.parallax_rad * 180 / M_PI, e.class_votes[1], e.class_votes[2], e.class_votes[3], e.class_votes[4],
                 e.heard ? ", heard" : "", e.called ? ", called" : "", nearest.c_str(), nearest_m);
        }
      }
      if (!have_truth) return;
      for (const auto& ts : truth.sources) {
        const Eigen::Vector2d p(ts.position_m[0], ts.position_m[1]);
        double best = std::numeric_limits<double>::infinity(), best_conv = best, best_placed = best;
        const OnlineSoundMap::Source* placed = nullptr;
        for (const auto& s : sources) {
          const double d = (to_world(s.position_m) - p).norm();
          best = std::min(best, d);
          if (s.state != OnlineSoundMap::Source::kInitialising) best_conv = std::min(best_conv, d);
          if (s.has_position && d < best_placed) {
            best_placed = d;
            placed = &s;
          }
        }
        static const char* kKinds[] = {"?", "voice", "music", "alarm", "noise"};
        printf(
            "  truth %-18s %-5s (%5.2f, %5.2f): nearest source %.3f m, nearest converged %.3f m, "
            "nearest placed %.3f m",
            ts.name.c_str(), ts.kind >= 1 && ts.kind <= 4 ? kKinds[ts.kind] : "?", p.x(), p.y(),
            best, best_conv, best_placed);
        if (placed)
          printf(" (%s%s)", ClassName(placed->sound_class), placed->is_person ? ", person" : "");
        printf("\n");
      }
    };

    int64_t next_report = report_every_s > 0 ? first_utime + static_cast<int64_t>(report_every_s * 1e6)
                                             : std::numeric_limits<int64_t>::max();
    int64_t last = first_utime;
    for (auto& kv : inputs) {
      while (kv.first >= next_report) {
        report(next_report, false);
        next_report += static_cast<int64_t>(report_every_s * 1e6);
      }
      kv.second();
      last = kv.first;
    }
    printf("log %s: %ld DOA messages, %ld DOAs (", log_path.c_str(), static_cast<long>(doa_msgs),
           static_cast<long>(doa_sources));
    for (const auto& k : kinds) printf(" kind %d: %ld", k.first, static_cast<long>(k.second));
    printf(" ), largest DOA track id %ld%s\n", static_cast<long>(max_track), no_anchors ? ", SLAM_ANCHORS ignored" : "");
    if (classifier)
      printf("relocalised: the source classifier took %.2f s of CPU\n", classifier_cpu_s);
    if (localiser && localiser->samples_seen() > 0)
      printf("relocalised: the localiser took %.2f s of CPU for %.1f s of audio = %.2f%% of a core\n", localiser_cpu_s,
             static_cast<double>(localiser->samples_seen()) / geometry.sample_rate_hz,
             100 * localiser_cpu_s * geometry.sample_rate_hz / static_cast<double>(localiser->samples_seen()));
    report(last, true);
    if (joint && !slam_poses.empty()) {
      // §4.2 on the log: a pose node per DOA block at the trajectory's pose then, the CI map's
      // sources as the initial guess and for the association, everything solved together.
      auto pose_at = [&](int64_t t, Pose2* out) {
        auto after = slam_poses.lower_bound(t);
        if (after == slam_poses.end() || after == slam_poses.begin()) return false;
        const auto before = std::prev(after);
        if (after->first - before->first > 2000000) return false;
        const double a = static_cast<double>(t - before->first) / static_cast<double>(after->first - before->first);
        const Pose2 d = sarmap::sound_map::Between(before->second, after->second);
        *out = sarmap::sound_map::Compose(before->second, Pose2(a * d.x, a * d.y, a * d.yaw));
        return true;
      };
      std::vector<Pose2> poses;
      std::vector<std::vector<sarmap::sound_map::LogBearing>> bearings;
      const double max_el = options.map.max_abs_elevation_deg * M_PI / 180;
      for (const auto& [t0, m] : doa_log) {
        Pose2 pose, before, after;
        const int64_t t = t0 + doa_shift_us;
        if (!pose_at(t, &pose)) continue;
        // As the map does: DOAs heard while the robot turns lag its heading (the localiser's
        // 256 ms windows and tracker).
        if (pose_at(t - 250000, &before) && pose_at(t + 250000, &after) &&
            std::abs(sarmap::sound_map::WrapAngle(after.yaw - before.yaw)) / 0.5 >
                options.map.max_turn_rate_deg_per_s * M_PI / 180)
          continue;
        std::vector<sarmap::sound_map::LogBearing> b;
        for (const auto& src : m.sources) {
          if (src.kind == sarmap::doa_source_t::KIND_ANGLE_1D) continue;
          if (options.map.three_d && std::abs(src.elevation_rad) > max_el) continue;  // the robot's motors
          sarmap::sound_map::LogBearing lb;
          lb.azimuth_rad = src.azimuth_rad;
          lb.elevation_rad = src.elevation_rad;
          lb.sigma_rad = std::sqrt(std::max(0.0, src.covariance[0]));
          b.push_back(lb);
        }
        if (b.empty()) continue;
        poses.push_back(pose);
        bearings.push_back(b);
      }
      const auto ci = map.Sources(last);
      std::vector<Eigen::Vector3d> init;
      for (const auto& src : ci) init.push_back(src.position_m);
      sarmap::sound_map::LogJointOptions jo;
      jo.doa_sigma_floor_deg = options.map.doa_sigma_floor_deg;
      jo.gate_chi2 = options.map.gate_chi2;
      jo.odometry_sigma_floor_m *= joint_pose_freedom;
      jo.odometry_sigma_m_per_m *= joint_pose_freedom;
      jo.odometry_sigma_floor_deg *= joint_pose_freedom;
      jo.odometry_sigma_deg_per_m *= joint_pose_freedom;
      sarmap::sound_map::JointProblem2d problem;
      const auto rep = sarmap::sound_map::SolveJointFromLog(
          poses, bearings, init, sarmap::sound_map::MountFromRobot(robot), options.map.three_d, jo, &problem);
      printf("joint optimisation (§4.2) on the log: %zu pose nodes, %zu bearing edges to %zu sources, solved in %.3f s "
             "(%d iterations), cost %.1f -> %.1f\n",
             problem.poses.size(), problem.sound_edges.size(), init.size(), rep.solve_seconds, rep.iterations,
             rep.initial_cost, rep.final_cost);
      if (have_truth) {
        for (const auto& ts : truth.sources) {
          const Eigen::Vector2d p(ts.position_m[0], ts.position_m[1]);
          double best_ci = std::numeric_limits<double>::infinity(), best_joint = best_ci;
          for (size_t j = 0; j < init.size(); ++j) {
            if (!problem.source_observed[j]) continue;
            best_ci = std::min(best_ci, (to_world(init[j]) - p).norm());
            best_joint = std::min(best_joint, (to_world(problem.sources[j]) - p).norm());
          }
          printf("  truth %-18s nearest source: CI map %.3f m, joint %.3f m\n", ts.name.c_str(), best_ci, best_joint);
        }
      }
    }
    if (live_msgs > 0) {
      int converged = 0;
      int64_t max_id = 0;
      for (const auto& s : live.sources) {
        converged += s.state == sarmap::sound_source_t::STATE_CONVERGED;
        max_id = std::max(max_id, s.id);
      }
      printf("logged %s (the live node, %ld messages): last has %d sources (%d converged), largest id %ld\n",
             options.sound_map_channel.c_str(), static_cast<long>(live_msgs), live.num_sources, converged,
             static_cast<long>(max_id));
      for (const auto& ts : truth.sources) {
        const Eigen::Vector2d p(ts.position_m[0], ts.position_m[1]);
        double best = std::numeric_limits<double>::infinity(), best_conv = best;
        for (const auto& s : live.sources) {
          const double d = (to_world(Eigen::Vector3d(s.position_m[0], s.position_m[1], 0)) - p).norm();
          best = std::min(best, d);
          if (s.state == sarmap::sound_source_t::STATE_CONVERGED) best_conv = std::min(best_conv, d);
        }
        printf("  truth %-18s nearest live source %.3f m, nearest converged %.3f m\n", ts.name.c_str(), best, best_conv);
      }
    }
    return 0;
  });
}
