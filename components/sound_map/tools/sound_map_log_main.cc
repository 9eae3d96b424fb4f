// sarmap-log-sound-map: replays the sound map's inputs from an LCM log (POSE, DOA_MAP,
// SLAM_ANCHORS, PEOPLE_AUDIO, MAP) through sarmap-sound-map's own adapter (SoundMapNode) on the
// log's clock (logtools::NodeReplay): its stamp gates, its time-ordered queue and its publishing,
// as fast as the CPU allows. Prints the final map and, when the log holds SIM_TRUTH, each true
// source's error against its nearest mapped source.
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
#include <ctime>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/command_auth.h"
#include "common/decode.h"
#include "common/message_conversions.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "log-tools/lcm_log_reader.h"
#include "log-tools/lcm_log_writer.h"
#include "log-tools/node_replay.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/sim_truth_t.hpp"
#include "sound_localisation/doa_stream.h"
#include "sound_localisation/sound_localisation_node.h"
#include "sound_localisation/source_class.h"
#include "sound_map/joint_optimizer.h"
#include "sound_map/sound_map_messages.h"
#include "sound_map/sound_map_node.h"

namespace {

using sarmap::common::Utime;
using sarmap::sound_map::OnlineSoundMap;
using sarmap::sound_map::Pose2;

template <class T>
bool Decode(const sarmap::logtools::LogEvent& e, T* msg) {
  return sarmap::common::DecodeMessage(e.data.data(), e.data.size(), msg);
}

template <class T>
std::vector<uint8_t> Encode(const T& msg) {
  std::vector<uint8_t> data(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(data.data(), 0, static_cast<int>(data.size()));
  return data;
}

const char* ClassName(int c) {
  return sarmap::sound::SoundClassName(static_cast<sarmap::sound::SoundClass>(c));
}

// A POSE message of a planar pose: what --truth-poses and --trajectory put in place of POSE.
sarmap::pose_t PoseMessage(Utime utime, const Pose2& pose, const Eigen::Matrix3d& covariance) {
  sarmap::pose_t m{};
  m.header.utime = utime;
  m.header.frame = "map";
  m.node_id = -1;
  sarmap::common::FromRigid3d(
      sarmap::common::Rigid3d::FromRigid2d(sarmap::common::Rigid2d(pose.x, pose.y, pose.yaw)),
      m.position_m, m.orientation);
  sarmap::common::SetPlanarCovariance(covariance, m.covariance);
  return m;
}

// Each source's position (by id) of the SOUND_MAPs published at each map time.
using SourcesByTime = std::map<Utime, std::map<int64_t, Eigen::Vector3d>>;
// Keeps the first SOUND_MAP at each time: a node's final map (Finish) may repeat the time of
// its last input.
void KeepSources(const sarmap::sound_map_t& m, SourcesByTime* maps) {
  const auto [at, first] = maps->try_emplace(m.header.utime);
  if (!first) return;
  for (const auto& src : m.sources)
    at->second[src.id] = Eigen::Vector3d(src.position_m[0], src.position_m[1], src.position_m[2]);
}

// A heard keyword direction (PEOPLE_AUDIO), for --heard-check.
struct Heard {
  Utime utime = 0;
  OnlineSoundMap::Doa direction;
  std::string keyword;
};

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-sound-map", [&] {
    using namespace sarmap;
    common::ArgParser parser(
        "sarmap-log-sound-map",
        "Replays POSE, DOA_MAP, SLAM_ANCHORS, PEOPLE_AUDIO and MAP from an LCM log through\n"
        "sarmap-sound-map's own adapter on the log's clock and compares the result with "
        "SIM_TRUTH.");
    common::NodeArgs node_args;
    std::string log_path, truth_channel = "SIM_TRUTH", doa_trace;
    bool no_anchors = false, doa_check = false, truth_poses_in = false, heard_check = false;
    double report_every_s = 0;
    std::string relocalise_config, relocalise_array;
    std::vector<std::string> relocalise_overrides;
    double doa_shift_s = 0;
    bool pose_check = false, joint = false, trace_evidence = false;
    double joint_pose_freedom = 1.0, anchor_covariance_scale = 1.0;
    std::string trajectory_path;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddSwitch("--no-anchors", &no_anchors,
                     "ignore SLAM_ANCHORS (POSE alone: the robot's motion)");
    parser.AddSwitch(
        "--heard-check", &heard_check,
        "print every heard keyword direction (PEOPLE_AUDIO) against the true bearings");
    parser.AddSwitch("--doa-check", &doa_check,
                     "compare every DOA with the true bearings of the SIM_TRUTH sources");
    parser.AddSwitch(
        "--truth-poses", &truth_poses_in,
        "diagnosis: SIM_TRUTH robot poses instead of POSE and SLAM_ANCHORS (map = world frame)");
    parser.AddFlag("--doa-trace", &doa_trace,
                   "with --doa-check: print every DOA nearest this true source");
    parser.AddFlag("--truth-channel", &truth_channel, "simulator ground truth channel");
    parser.AddFlag("--relocalise", &relocalise_config,
                   "run sarmap-sound-localisation's adapter (this config file) over the log's "
                   "AUDIO and map its "
                   "DOAs instead of the log's");
    parser.AddFlag(
        "--array", &relocalise_array,
        "with --relocalise: the microphone array file (default: the config file's `array`)");
    parser.AddRepeated("--loc-set", &relocalise_overrides,
                       "with --relocalise: override a sarmap-sound-localisation option (k=v, e.g. "
                       "map_localiser.onset_rise_db=0)");
    parser.AddFlag("--doa-shift", &doa_shift_s,
                   "diagnosis: add this many seconds to every DOA time (does the map improve with "
                   "a timing fix?)");
    parser.AddSwitch(
        "--pose-check", &pose_check,
        "print POSE against SIM_TRUTH along the path (every 3 s) and its RMS against a time lag");
    parser.AddFlag(
        "--trajectory", &trajectory_path,
        "diagnosis: poses from this file (t x y yaw per line, sarmap-slam-offline --output on the "
        "same log) instead of POSE, SLAM_ANCHORS ignored: try SLAM settings offline");
    parser.AddSwitch(
        "--joint", &joint,
        "also solve the joint optimisation (§4.2) of the trajectory (POSE, or the truth with "
        "--truth-poses) and the final map's sources from every DOA, and score it");
    parser.AddFlag("--joint-pose-freedom", &joint_pose_freedom,
                   "with --joint: multiplies the trajectory's relative-pose sigmas (larger lets "
                   "the sound bend it)");
    parser.AddFlag(
        "--anchor-covariance-scale", &anchor_covariance_scale,
        "diagnosis: multiply SLAM_ANCHORS' covariance by this (with use_slam_covariance)");
    parser.AddSwitch("--trace-evidence", &trace_evidence,
                     "diagnosis: at the end and at every --report-every, print every source "
                     "where the bearings cross (map.evidence) with its support and the nearest "
                     "true source");
    parser.AddFlag(
        "--report-every", &report_every_s,
        "also print the map and its errors every this many seconds of the log (0: end only)");
    std::string write_map;
    parser.AddFlag("--write-map", &write_map,
                   "write every SOUND_MAP the replay publishes to this LCM log (at the log time "
                   "it is published), for sarmap-log people-map --sound-map");
    const auto parsed = common::ParseNodeOptions<sound_map::SoundMapNodeOptions>(
        &parser, &node_args, argc, argv, "config/sound_map.yaml");
    if (!parsed) return 0;
    const sound_map::SoundMapNodeOptions& options = *parsed;
    const auto robot = common::LoadRobot(options.robot_config);
    const bool relocalise = !relocalise_config.empty();
    if (relocalise && doa_shift_s != 0)
      throw common::ArgError("--doa-shift shifts the log's DOAs; with --relocalise there are none");
    if (!trajectory_path.empty() && truth_poses_in)
      throw common::ArgError("--trajectory and --truth-poses exclude each other");

    // --trajectory: the poses that replace POSE, in time order.
    std::map<Utime, Pose2> slam_poses;  // map_from_base by utime, as the map received them
    std::vector<std::pair<Utime, Pose2>> file_poses;
    if (!trajectory_path.empty()) {
      no_anchors = true;
      std::ifstream in(trajectory_path);
      if (!in) throw std::runtime_error("cannot read trajectory " + trajectory_path);
      for (std::string line; std::getline(in, line);) {
        double ts, x, y, yaw;
        if (line.empty() || line[0] == '#' ||
            std::sscanf(line.c_str(), "%lf %lf %lf %lf", &ts, &x, &y, &yaw) != 4)
          continue;
        file_poses.emplace_back(std::llround(ts * 1e6), Pose2(x, y, yaw));
      }
      if (file_poses.empty()) throw std::runtime_error("no poses in " + trajectory_path);
      std::stable_sort(file_poses.begin(), file_poses.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
    }
    // What sarmap-slam adds to a node's covariance for the local match (pose_sigma_*).
    const Eigen::Matrix3d file_pose_covariance =
        Eigen::Vector3d(0.02 * 0.02, 0.02 * 0.02, std::pow(M_PI / 180, 2)).asDiagonal();

    // The adapters on the log's clock, as they ran: the sound map's (and with --relocalise the
    // localisation's, whose DOAs it then maps). A replay starts empty and saves nothing.
    common::Node node("sarmap-log-sound-map", "memq://");
    if (!node_args.bus_key_file.empty())
      node.SetBusKey(common::LoadAuthKeyFile(node_args.bus_key_file));
    sound_map::SoundMapNodeOptions replay_options = options;
    replay_options.state_file = "";
    replay_options.resume = false;
    std::unique_ptr<sound::SoundLocalisationNode> localisation;
    std::vector<std::string> audio_channels;
    if (relocalise) {
      auto loc_options = common::LoadOptions<sound::SoundLocalisationOptions>(
          common::ResolveConfigPath(relocalise_config), relocalise_overrides);
      if (!relocalise_array.empty()) loc_options.array = relocalise_array;
      loc_options.array = common::ResolveConfigPath(loc_options.array);
      // The sound map reads the localisation's map stream (its only stream when it has none).
      replay_options.doa_channel = loc_options.map_doa_channel.empty()
                                       ? loc_options.doa_channel
                                       : loc_options.map_doa_channel;
      audio_channels = loc_options.audio_channels;
      audio_channels.push_back(loc_options.audio_channel);
      localisation = std::make_unique<sound::SoundLocalisationNode>(loc_options, &node);
    }
    sound_map::SoundMapNode sound_map_node(replay_options, &node);
    const OnlineSoundMap& map = sound_map_node.map();
    logtools::NodeReplay replay(&node);

    // Every DOA the map is given, as it is given.
    std::vector<std::pair<Utime, doa_t>> doa_log;
    int64_t doa_msgs = 0, doa_sources = 0, max_track = -1;
    std::map<int, int64_t> kinds;
    replay.Capture(replay_options.doa_channel,
                   [&](const std::string&, const std::vector<uint8_t>& data) {
                     doa_t m;
                     if (!common::DecodeMessage(data.data(), data.size(), &m)) return;
                     ++doa_msgs;
                     for (const auto& s : m.sources) {
                       ++doa_sources;
                       ++kinds[s.kind];
                       max_track = std::max(max_track, s.track_id);
                     }
                     doa_log.emplace_back(m.header.utime, std::move(m));
                   });
    // Each source's position in every SOUND_MAP the replay publishes, by the map's time.
    SourcesByTime published;
    Utime last_published = 0;
    std::unique_ptr<logtools::LcmLogWriter> map_writer;
    if (!write_map.empty()) map_writer = std::make_unique<logtools::LcmLogWriter>(write_map);
    replay.Capture(replay_options.sound_map_channel,
                   [&](const std::string& channel, const std::vector<uint8_t>& data) {
                     if (map_writer) map_writer->WriteBytes(channel, data, replay.now_us());
                     sound_map_t m;
                     if (!common::DecodeMessage(data.data(), data.size(), &m)) return;
                     last_published = m.header.utime;
                     KeepSources(m, &published);
                   });

    // What the log says besides the inputs: the truth, and the live node's last SOUND_MAP.
    sim_truth_t truth;
    bool have_truth = false;
    std::map<Utime, Pose2> truth_poses;               // world_from_base by utime
    std::map<Utime, std::vector<char>> truth_active;  // SIM_TRUTH time -> each source sounding
    std::map<int64_t, Utime> node_utime;              // SLAM node id -> first POSE time naming it
    std::vector<std::pair<Utime, std::vector<std::pair<int64_t, Pose2>>>> anchor_log;
    std::vector<Heard> heard_log;
    sound_map_t live;  // the last SOUND_MAP the running node published, if logged
    SourcesByTime live_maps;  // the logged live node's
    int64_t live_msgs = 0;
    const Utime doa_shift_us = std::llround(doa_shift_s * 1e6);
    size_t next_file_pose = 0;
    Utime first_utime = 0;
    Utime next_report = std::numeric_limits<Utime>::max();

    // The SLAM map frame starts at the robot's first pose; the truth is in the world frame:
    // world_from_map = truth pose ∘ POSE^-1 at the first POSE (nearest truth message).
    auto truth_at = [&](Utime t) {
      auto it = truth_poses.lower_bound(t);
      if (it == truth_poses.end()) --it;
      return it->second;
    };
    // Which true sources sounded at time t (the SIM_TRUTH before it); empty: unknown.
    auto active_at = [&](Utime t) -> std::vector<char> {
      auto it = truth_active.upper_bound(t);
      if (it == truth_active.begin()) return {};
      return std::prev(it)->second;
    };
    auto world_from_map = [&] {
      if (truth_poses.empty() || slam_poses.empty()) return Pose2();
      const auto& first = *slam_poses.begin();
      return sound_map::Compose(truth_at(first.first), sound_map::Between(first.second, Pose2()));
    };
    auto to_world = [&](const Eigen::Vector3d& p) {
      const Pose2 w = sound_map::Compose(world_from_map(), Pose2(p.x(), p.y(), 0));
      return Eigen::Vector2d(w.x, w.y);
    };
    // The map at `now`: its sources and, with the truth, each true source's nearest.
    auto report = [&](Utime now, bool final_report) {
      const auto sources = map.Sources(now);
      int converged = 0;
      for (const auto& s : sources) converged += s.state == OnlineSoundMap::Source::kConverged;
      const auto& c = map.counters();
      printf(
          "t=%6.1f s: %zu sources (%d converged), born %ld, pruned %ld (+%ld mirrors), DOAs used "
          "%ld, "
          "tentative %ld, gated out %ld, dropped while turning %ld, too steep %ld, "
          "on the robot's path %ld\n",
          (now - first_utime) * 1e-6, sources.size(), converged,
          static_cast<long>(c.doa_new_sources), static_cast<long>(c.sources_pruned),
          static_cast<long>(c.mirrors_pruned), static_cast<long>(c.doa_used),
          static_cast<long>(c.doa_tentative), static_cast<long>(c.doa_gated_out),
          static_cast<long>(c.doa_while_turning), static_cast<long>(c.doa_too_steep),
          static_cast<long>(c.sources_on_path));
      if (final_report) {
        for (const auto& s : sources) {
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(
              s.covariance.topLeftCorner<2, 2>());
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
      if (trace_evidence) {
        printf("  where the bearings cross (%zu rays kept, %ld solves):\n", map.evidence_rays(),
               static_cast<long>(c.evidence_solves));
        for (const auto& e : map.evidence_sources()) {
          const Eigen::Vector2d w =
              to_world(Eigen::Vector3d(e.position_m.x(), e.position_m.y(), 0));
          std::string nearest = "-";
          double nearest_m = std::numeric_limits<double>::infinity();
          for (const auto& ts : truth.sources) {
            const double d = (w - Eigen::Vector2d(ts.position_m[0], ts.position_m[1])).norm();
            if (d < nearest_m) nearest_m = d, nearest = ts.name;
          }
          printf(
              "    (%6.2f, %6.2f) world (%6.2f, %6.2f): %5.1f rays, %3.0f strong, std %.2f m, "
              "parallax %3.0f deg, "
              "votes v%.0f a%.0f m%.0f u%.0f%s%s; nearest true %s %.2f m\n",
              e.position_m.x(), e.position_m.y(), w.x(), w.y(), e.rays, e.strong_rays,
              e.largest_sigma_m, e.parallax_rad * 180 / M_PI, e.class_votes[1], e.class_votes[2],
              e.class_votes[3], e.class_votes[4], e.heard ? ", heard" : "",
              e.called ? ", called" : "", nearest.c_str(), nearest_m);
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

    double audio_s = 0, audio_cpu_s = 0;  // --relocalise: audio replayed, and its CPU time
    int64_t audio_events = 0;
    auto is_audio = [&](const std::string& channel) {
      return std::find(audio_channels.begin(), audio_channels.end(), channel) !=
             audio_channels.end();
    };
    // Which events the adapters take (some rewritten, e.g. --doa-shift) and what the diagnosis
    // keeps of them.
    auto feed = [&](logtools::LogEvent* e) {
      // --trajectory: each file pose once the log reaches its time.
      for (; next_file_pose < file_poses.size() &&
             file_poses[next_file_pose].first <= e->timestamp_us;
           ++next_file_pose) {
        const auto& [t, pose] = file_poses[next_file_pose];
        slam_poses[t] = pose;
        replay.Inject(replay_options.pose_channel,
                      Encode(PoseMessage(t, pose, file_pose_covariance)));
      }
      if (e->channel == truth_channel) {
        sim_truth_t m;
        if (!Decode(*e, &m)) return false;
        truth = m;
        have_truth = true;
        std::vector<char>& active = truth_active[m.header.utime];
        for (const auto& ts : m.sources) active.push_back(ts.active);
        const Eigen::Quaterniond q(m.robot_orientation[0], m.robot_orientation[1],
                                   m.robot_orientation[2], m.robot_orientation[3]);
        const Eigen::Vector3d x = q.normalized() * Eigen::Vector3d::UnitX();
        const Pose2 tp(m.robot_position_m[0], m.robot_position_m[1], std::atan2(x.y(), x.x()));
        truth_poses[m.header.utime] = tp;
        if (truth_poses_in) {
          slam_poses[m.header.utime] = tp;
          replay.Inject(
              replay_options.pose_channel,
              Encode(PoseMessage(m.header.utime, tp, Eigen::Matrix3d::Identity() * 1e-6)));
        }
        return false;
      }
      if (e->channel == replay_options.pose_channel) {
        if (truth_poses_in || !file_poses.empty()) return false;
        pose_t m;
        if (!Decode(*e, &m)) return true;  // the node reports it
        const Utime t = m.header.utime;
        if (m.node_id >= 0 && !node_utime.count(m.node_id)) node_utime[m.node_id] = t;
        slam_poses[t] = sound_map::ToPose2(sound_map::PlanarPose(m));
        return true;
      }
      if (e->channel == replay_options.doa_channel) {
        if (relocalise) return false;
        if (doa_shift_us == 0) return true;
        doa_t m;
        if (!Decode(*e, &m)) return true;
        m.header.utime += doa_shift_us;
        e->data = Encode(m);
        return true;
      }
      if (relocalise && is_audio(e->channel)) {
        // Handled here, to time the localisation (and the map on the DOAs it publishes).
        audio_frame_t a;
        if (Decode(*e, &a) && a.sample_rate_hz > 0)
          audio_s += static_cast<double>(a.num_samples) / a.sample_rate_hz;
        const std::clock_t c0 = std::clock();
        replay.Inject(e->channel, e->data);
        audio_cpu_s += static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
        ++audio_events;
        return false;
      }
      if (e->channel == replay_options.anchors_channel) {
        if (no_anchors || truth_poses_in) return false;
        slam_anchors_t m;
        if (!Decode(*e, &m)) return true;
        common::Rigid2d current;
        std::vector<std::pair<int64_t, common::Rigid2d>> anchors;
        Eigen::MatrixXd cov;
        if (sound_map::AnchorsFromMessage(m, &current, &anchors, &cov)) {
          std::vector<std::pair<int64_t, Pose2>> planar;
          for (const auto& [id, pose] : anchors) planar.emplace_back(id, sound_map::ToPose2(pose));
          anchor_log.emplace_back(m.header.utime, planar);
        }
        if (anchor_covariance_scale != 1.0) {
          for (auto& row : m.covariance)
            for (double& c : row) c *= anchor_covariance_scale;
          e->data = Encode(m);
        }
        return true;
      }
      if (e->channel == replay_options.people_audio_channel) {
        people_detections_t m;
        if (!Decode(*e, &m)) return true;
        const auto heard = sound_map::HeardDirections(m);
        std::vector<std::string> keywords;  // HeardDirections' detections, in order
        for (const auto& d : m.detections)
          if (d.cue == person_detection_t::CUE_HEARD && std::isfinite(d.azimuth_rad))
            keywords.push_back(d.keyword + "' conf " + std::to_string(d.confidence).substr(0, 4) +
                               " '");
        for (size_t i = 0; i < heard.size(); ++i)
          heard_log.push_back({m.header.utime, heard[i], i < keywords.size() ? keywords[i] : ""});
        return true;
      }
      if (e->channel == replay_options.sound_map_channel) {
        sound_map_t m;
        if (Decode(*e, &m)) {
          KeepSources(m, &live_maps);
          live = std::move(m);
          ++live_msgs;
        }
        return false;  // the replay's own map is published there
      }
      return !replay_options.site_map_channel.empty() &&
             e->channel == replay_options.site_map_channel;
    };
    const std::clock_t cpu_start = std::clock();
    const auto stats = replay.Run(log_path, [&](logtools::LogEvent* e) {
      while (e->timestamp_us >= next_report) {
        report(next_report, false);
        next_report += std::llround(report_every_s * 1e6);
      }
      const bool fed = feed(e);
      if (fed && first_utime == 0) {  // the replay's time origin: its first input
        first_utime = e->timestamp_us;
        if (report_every_s > 0) next_report = first_utime + std::llround(report_every_s * 1e6);
      }
      return fed;
    });
    for (; next_file_pose < file_poses.size(); ++next_file_pose) {
      const auto& [t, pose] = file_poses[next_file_pose];
      slam_poses[t] = pose;
      replay.Inject(replay_options.pose_channel,
                    Encode(PoseMessage(t, pose, file_pose_covariance)));
    }
    sound_map_node.Finish();
    replay.Drain();
    for (const auto& p : stats.problems)
      printf("warning: %s\n", logtools::DescribeProblem(p).c_str());
    if (stats.events_fed + audio_events == 0 && slam_poses.empty())
      throw std::runtime_error("no sound map input in " + log_path);
    if (sound_map_node.off_clock() > 0 || sound_map_node.dropped_late() > 0)
      printf(
          "inputs dropped as the node drops them: %lld stamped far from their stream's clock, %lld "
          "late\n",
          static_cast<long long>(sound_map_node.off_clock()),
          static_cast<long long>(sound_map_node.dropped_late()));
    const Utime last = last_published;
    printf("replayed %lld of %lld events in %.2f s of CPU\n",
           static_cast<long long>(stats.events_fed + audio_events),
           static_cast<long long>(stats.events_read),
           static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
    if (!truth_poses.empty() && !slam_poses.empty()) {
      const Pose2 w = world_from_map();
      printf("world_from_map (first POSE vs SIM_TRUTH): (%.3f, %.3f, %.2f deg)\n", w.x, w.y,
             w.yaw * 180 / M_PI);
    }
    if (!truth_poses.empty()) {
      const Pose2 wfm = world_from_map();
      double max_pos = 0, max_yaw = 0, sum2 = 0;
      for (const auto& [t, p] : slam_poses) {
        const Pose2 w = sound_map::Compose(wfm, p);
        const Pose2 tr = truth_at(t);
        const double e = std::hypot(w.x - tr.x, w.y - tr.y);
        max_pos = std::max(max_pos, e);
        sum2 += e * e;
        max_yaw = std::max(max_yaw, std::abs(sound_map::WrapAngle(w.yaw - tr.yaw)));
      }
      printf(
          "POSE against SIM_TRUTH: %zu poses, RMS %.3f m, max %.3f m, max heading error %.2f deg\n",
          slam_poses.size(), std::sqrt(sum2 / std::max<size_t>(1, slam_poses.size())), max_pos,
          max_yaw * 180 / M_PI);
      if (pose_check && !slam_poses.empty()) {
        const Utime t0 = slam_poses.begin()->first;
        Utime next = t0;
        for (const auto& [t, p] : slam_poses) {
          if (t < next) continue;
          next = t + 3000000;
          const Pose2 w = sound_map::Compose(wfm, p);
          const Pose2 tr = truth_at(t);
          printf("  t %5.1f truth (%5.2f %5.2f %6.1f) err (%+.2f %+.2f %+.2f deg)\n",
                 (t - t0) * 1e-6, tr.x, tr.y, tr.yaw * 180 / M_PI, w.x - tr.x, w.y - tr.y,
                 sound_map::WrapAngle(w.yaw - tr.yaw) * 180 / M_PI);
        }
        for (double lag = -0.6; lag <= 0.61; lag += 0.1) {
          double s2 = 0, y2 = 0;
          for (const auto& [t, p] : slam_poses) {
            const Pose2 w = sound_map::Compose(wfm, p);
            const Pose2 tr = truth_at(t + static_cast<Utime>(lag * 1e6));
            s2 += std::pow(w.x - tr.x, 2) + std::pow(w.y - tr.y, 2);
            y2 += std::pow(sound_map::WrapAngle(w.yaw - tr.yaw), 2);
          }
          printf("  lag %+.1f s: RMS %.3f m, heading RMS %.2f deg\n", lag,
                 std::sqrt(s2 / slam_poses.size()), std::sqrt(y2 / slam_poses.size()) * 180 / M_PI);
        }
        // The sound map's anchors (SLAM nodes) as SLAM_ANCHORS gives them, against the truth at
        // the time their node was current, every 5 s.
        Utime next_anchor = 0;
        for (const auto& [t, anchors] : anchor_log) {
          if (t < next_anchor) continue;
          next_anchor = t + 5000000;
          for (const auto& [id, pose] : anchors) {
            auto nt = node_utime.find(id);
            if (nt == node_utime.end()) continue;
            const Pose2 w = sound_map::Compose(wfm, pose);
            const Pose2 tr = truth_at(nt->second);
            printf(
                "  anchors t %5.1f: node %ld (current at %5.1f s) err (%+.2f %+.2f m, %+.2f deg)\n",
                (t - t0) * 1e-6, static_cast<long>(id), (nt->second - t0) * 1e-6, w.x - tr.x,
                w.y - tr.y, sound_map::WrapAngle(w.yaw - tr.yaw) * 180 / M_PI);
          }
        }
      }
    }
    const auto mount = sound_map::MountFromRobot(robot);
    if (heard_check && have_truth) {
      // Each heard keyword direction against the true bearing (truth robot pose, array mount)
      // of the nearest true source.
      for (const auto& h : heard_log) {
        const Pose2 arr =
            sound_map::Compose(truth_at(h.utime), Pose2(mount.x_m, mount.y_m, mount.yaw_rad));
        std::string nearest;
        double best = 1e9;
        for (const auto& ts : truth.sources) {
          const double b = std::atan2(ts.position_m[1] - arr.y, ts.position_m[0] - arr.x) - arr.yaw;
          const double e = sound_map::WrapAngle(h.direction.azimuth_rad - b) * 180 / M_PI;
          if (std::abs(e) < std::abs(best)) {
            best = e;
            nearest = ts.name;
          }
        }
        printf("  heard t=%6.2f track %3ld '%s' az %7.1f: nearest true %s (%+.1f deg)\n",
               (h.utime - first_utime) * 1e-6, static_cast<long>(h.direction.track_id),
               common::EscapeForLog(h.keyword).c_str(), h.direction.azimuth_rad * 180 / M_PI,
               nearest.c_str(), best);
      }
    }
    if (doa_check && have_truth) {
      // Each DOA's azimuth against the true bearing (truth robot pose, array mount) of the
      // nearest true source: how good are the localiser's bearings?
      std::map<std::string, std::vector<double>> errors, signed_errors;
      std::map<std::string, std::map<int, int>> classes;  // DOAs within 10 deg of a sounding source
      std::vector<double> all;
      for (const auto& [t, m] : doa_log) {
        const Pose2 base = truth_at(t);
        const Pose2 arr = sound_map::Compose(base, Pose2(mount.x_m, mount.y_m, mount.yaw_rad));
        const std::vector<char> active = active_at(t);
        for (const auto& s : m.sources) {
          double best = 1e9, signed_best = 0;
          std::string name;
          bool best_active = false;
          for (size_t j = 0; j < truth.sources.size(); ++j) {
            const auto& ts = truth.sources[j];
            double b = std::atan2(ts.position_m[1] - arr.y, ts.position_m[0] - arr.x) - arr.yaw;
            // Linear arrays: the angle to the array's x axis (0..pi), in the plane |bearing|.
            if (s.kind == doa_source_t::KIND_ANGLE_1D) b = std::abs(sound_map::WrapAngle(b));
            const double se = sound_map::WrapAngle(s.azimuth_rad - b) * 180 / M_PI;
            const bool sounding = j < active.size() && active[j];
            // A sounding source takes precedence over a silent one a little nearer.
            if ((sounding && !best_active && std::abs(se) < 10) ||
                ((sounding || !best_active) && std::abs(se) < best)) {
              best = std::abs(se);
              signed_best = se;
              name = ts.name;
              best_active = sounding;
            }
          }
          errors[name].push_back(best);
          if (best < 10 && best_active) ++classes[name][s.sound_class];
          if (name == doa_trace)
            printf(
                "  trace t=%6.2f robot (%5.2f, %5.2f, %6.1f deg) track %3ld doa %7.1f true %7.1f "
                "err %6.1f sigma %.1f\n",
                (t - doa_log.front().first) * 1e-6, base.x, base.y, base.yaw * 180 / M_PI,
                static_cast<long>(s.track_id), s.azimuth_rad * 180 / M_PI,
                (s.azimuth_rad * 180 / M_PI) - signed_best, signed_best,
                std::sqrt(s.covariance[0]) * 180 / M_PI);
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
      printf("DOA check: %zu DOAs, %d within 10 deg of a true source, median error %.1f deg\n",
             all.size(), within10, median(all));
      for (const auto& [name, v] : errors) {
        printf(
            "  nearest %-18s %4zu DOAs, median %.1f deg; within 25 deg: signed median %.1f deg; "
            "classes within 10 deg "
            "while it sounded:",
            name.c_str(), v.size(), median(v), median(signed_errors[name]));
        for (const auto& [c, n] : classes[name]) printf(" %s %d", ClassName(c), n);
        printf("\n");
      }
    }

    printf("log %s: %ld DOA messages, %ld DOAs (", log_path.c_str(), static_cast<long>(doa_msgs),
           static_cast<long>(doa_sources));
    for (const auto& k : kinds) printf(" kind %d: %ld", k.first, static_cast<long>(k.second));
    printf(" ), largest DOA track id %ld%s%s\n", static_cast<long>(max_track),
           no_anchors ? ", SLAM_ANCHORS ignored" : "",
           relocalise ? ", relocalised from AUDIO" : "");
    if (relocalise && audio_s > 0)
      printf(
          "relocalised: %.1f s of audio took %.2f s of CPU (the localisation, and the map on its "
          "DOAs) = %.2f%% "
          "of a core\n",
          audio_s, audio_cpu_s, 100 * audio_cpu_s / audio_s);
    report(last, true);
    if (joint && !slam_poses.empty()) {
      // §4.2 on the log: a pose node per DOA block at the trajectory's pose then, the CI map's
      // sources as the initial guess and for the association, everything solved together.
      auto pose_at = [&](Utime t, Pose2* out) {
        auto after = slam_poses.lower_bound(t);
        if (after == slam_poses.end() || after == slam_poses.begin()) return false;
        const auto before = std::prev(after);
        if (after->first - before->first > 2000000) return false;
        const double a = static_cast<double>(t - before->first) /
                         static_cast<double>(after->first - before->first);
        const Pose2 d = sound_map::Between(before->second, after->second);
        *out = sound_map::Compose(before->second, Pose2(a * d.x, a * d.y, a * d.yaw));
        return true;
      };
      std::vector<Pose2> poses;
      std::vector<std::vector<sound_map::LogBearing>> bearings;
      const double max_el = options.map.max_abs_elevation_deg * M_PI / 180;
      for (const auto& [t, m] : doa_log) {
        Pose2 pose, before, after;
        if (!pose_at(t, &pose)) continue;
        // As the map does: DOAs heard while the robot turns lag its heading (the localiser's
        // 256 ms windows and tracker).
        if (pose_at(t - 250000, &before) && pose_at(t + 250000, &after) &&
            std::abs(sound_map::WrapAngle(after.yaw - before.yaw)) / 0.5 >
                options.map.max_turn_rate_deg_per_s * M_PI / 180)
          continue;
        std::vector<sound_map::LogBearing> b;
        for (const auto& src : m.sources) {
          if (src.kind == doa_source_t::KIND_ANGLE_1D) continue;
          if (options.map.three_d && std::abs(src.elevation_rad) > max_el)
            continue;  // the robot's motors
          sound_map::LogBearing lb;
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
      sound_map::LogJointOptions jo;
      jo.doa_sigma_floor_deg = options.map.doa_sigma_floor_deg;
      jo.gate_chi2 = options.map.gate_chi2;
      jo.odometry_sigma_floor_m *= joint_pose_freedom;
      jo.odometry_sigma_m_per_m *= joint_pose_freedom;
      jo.odometry_sigma_floor_deg *= joint_pose_freedom;
      jo.odometry_sigma_deg_per_m *= joint_pose_freedom;
      sound_map::JointProblem2d problem;
      const auto rep = sound_map::SolveJointFromLog(poses, bearings, init, mount,
                                                    options.map.three_d, jo, &problem);
      printf(
          "joint optimisation (§4.2) on the log: %zu pose nodes, %zu bearing edges to %zu sources, "
          "solved in %.3f s "
          "(%d iterations), cost %.1f -> %.1f\n",
          problem.poses.size(), problem.sound_edges.size(), init.size(), rep.solve_seconds,
          rep.iterations, rep.initial_cost, rep.final_cost);
      if (have_truth) {
        for (const auto& ts : truth.sources) {
          const Eigen::Vector2d p(ts.position_m[0], ts.position_m[1]);
          double best_ci = std::numeric_limits<double>::infinity(), best_joint = best_ci;
          for (size_t j = 0; j < init.size(); ++j) {
            if (!problem.source_observed[j]) continue;
            best_ci = std::min(best_ci, (to_world(init[j]) - p).norm());
            best_joint = std::min(best_joint, (to_world(problem.sources[j]) - p).norm());
          }
          printf("  truth %-18s nearest source: CI map %.3f m, joint %.3f m\n", ts.name.c_str(),
                 best_ci, best_joint);
        }
      }
    }
    if (live_msgs > 0) {
      int converged = 0;
      int64_t max_id = 0;
      for (const auto& s : live.sources) {
        converged += s.state == sound_source_t::STATE_CONVERGED;
        max_id = std::max(max_id, s.id);
      }
      printf(
          "logged %s (the live node, %ld messages): last has %d sources (%d converged), largest id "
          "%ld\n",
          options.sound_map_channel.c_str(), static_cast<long>(live_msgs), live.num_sources,
          converged, static_cast<long>(max_id));
      // The replay against the live node at the same map times: the same sources at the same
      // places when the replay is the live pipeline.
      int compared = 0, same = 0;
      Utime first_apart = 0;
      for (const auto& [t, live_sources] : live_maps) {
        const auto r = published.find(t);
        if (r == published.end()) continue;
        ++compared;
        bool equal = r->second.size() == live_sources.size();
        for (const auto& [id, p] : live_sources) {
          const auto q = r->second.find(id);
          equal = equal && q != r->second.end() && (q->second - p).norm() <= 1e-3;
        }
        same += equal;
        if (!equal && first_apart == 0) first_apart = t;
      }
      printf(
          "  the replay published at %d of the live node's %zu times: the same sources within 1 mm "
          "at %d",
          compared, live_maps.size(), same);
      if (first_apart != 0) printf(", first apart at t=%.1f s", (first_apart - first_utime) * 1e-6);
      printf("\n");
      for (const auto& ts : truth.sources) {
        const Eigen::Vector2d p(ts.position_m[0], ts.position_m[1]);
        double best = std::numeric_limits<double>::infinity(), best_conv = best;
        for (const auto& s : live.sources) {
          const double d =
              (to_world(Eigen::Vector3d(s.position_m[0], s.position_m[1], 0)) - p).norm();
          best = std::min(best, d);
          if (s.state == sound_source_t::STATE_CONVERGED) best_conv = std::min(best_conv, d);
        }
        printf("  truth %-18s nearest live source %.3f m, nearest converged %.3f m\n",
               ts.name.c_str(), best, best_conv);
      }
    }
    return 0;
  });
}
