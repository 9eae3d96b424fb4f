// sarmap-log-sound-map: replays the sound map's inputs from an LCM log (POSE, DOA,
// SLAM_ANCHORS, PEOPLE_AUDIO) through the same OnlineSoundMap as sarmap-sound-map, in message
// time order, deterministically and as fast as the CPU allows; prints the final map and, when
// the log holds SIM_TRUTH, each true source's error against its nearest mapped source.
//
//   sarmap-log sound-map demo.lcmlog
//   sarmap-log sound-map demo.lcmlog --no-anchors            # from POSE alone
//   sarmap-log sound-map demo.lcmlog --set map.birth_min_observations=5
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <Eigen/Eigenvalues>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

#include "common/args.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "sarmap/sim_truth_t.hpp"
#include "sound_map/sound_map_messages.h"

namespace {

using sarmap::sound_map::OnlineSoundMap;
using sarmap::sound_map::Pose2;

template <class T>
bool Decode(const lcm::LogEvent& e, T* msg) {
  return msg->decode(e.data, 0, e.datalen) == e.datalen;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-sound-map", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log-sound-map",
        "Replays POSE, DOA, SLAM_ANCHORS and PEOPLE_AUDIO from an LCM log through the sound map\n"
        "(as sarmap-sound-map would, in message time order) and compares the result with SIM_TRUTH.");
    sarmap::common::NodeArgs node_args;
    std::string log_path, truth_channel = "SIM_TRUTH";
    bool no_anchors = false;
    double report_every_s = 0;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddSwitch("no-anchors", &no_anchors, "ignore SLAM_ANCHORS (POSE alone: the robot's motion)");
    parser.AddFlag("truth-channel", &truth_channel, "simulator ground truth channel");
    parser.AddFlag("report-every", &report_every_s, "also print the errors every this many seconds (0: end only)");
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
    int64_t doa_msgs = 0, doa_sources = 0, max_track = -1, first_utime = -1;
    std::map<int, int64_t> kinds;
    for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
      if (e->channel == options.pose_channel) {
        sarmap::pose_t m;
        if (!Decode(*e, &m)) continue;
        const Pose2 pose = sarmap::sound_map::PlanarPose(m);
        const Eigen::Matrix3d cov = sarmap::sound_map::PlanarCovariance(m.covariance);
        const int64_t t = m.header.utime, node = m.node_id;
        inputs.emplace(t, [&map, t, pose, cov, node] { map.OnPose(t, pose, cov, node); });
      } else if (e->channel == options.doa_channel) {
        sarmap::doa_t m;
        if (!Decode(*e, &m)) continue;
        ++doa_msgs;
        for (const auto& s : m.sources) {
          ++doa_sources;
          ++kinds[s.kind];
          max_track = std::max(max_track, s.track_id);
        }
        const auto doas = sarmap::sound_map::DoasFromMessage(m);
        const std::string device = m.device_id;
        const int64_t t = m.header.utime;
        inputs.emplace(t, [&map, t, device, doas] { map.OnDoa(t, device, doas); });
      } else if (e->channel == options.anchors_channel && !no_anchors) {
        sarmap::slam_anchors_t m;
        if (!Decode(*e, &m)) continue;
        Pose2 current;
        std::vector<std::pair<int64_t, Pose2>> anchors;
        Eigen::MatrixXd cov;
        if (!sarmap::sound_map::AnchorsFromMessage(m, &current, &anchors, &cov)) continue;
        const int64_t t = m.header.utime;
        inputs.emplace(t, [&map, t, current, anchors, cov] { map.OnSlamAnchors(t, current, anchors, cov); });
      } else if (e->channel == options.people_audio_channel) {
        sarmap::people_detections_t m;
        if (!Decode(*e, &m)) continue;
        const auto tracks = sarmap::sound_map::HeardTracks(m);
        const std::string device = m.sensor_id;
        inputs.emplace(m.header.utime, [&map, device, tracks] {
          for (int64_t tr : tracks) map.OnHeardPerson(device, tr);
        });
      } else if (e->channel == truth_channel) {
        sarmap::sim_truth_t m;
        if (!Decode(*e, &m)) continue;
        truth = m;
        have_truth = true;
      }
    }
    if (inputs.empty()) throw std::runtime_error("no sound map input in " + log_path);
    first_utime = inputs.begin()->first;

    auto report = [&](int64_t now, bool final_report) {
      const auto sources = map.Sources(now);
      int converged = 0;
      for (const auto& s : sources) converged += s.state == OnlineSoundMap::Source::kConverged;
      const auto& c = map.counters();
      printf("t=%6.1f s: %zu sources (%d converged), born %ld, pruned %ld (+%ld mirrors), DOAs used %ld, "
             "tentative %ld, gated out %ld\n",
             (now - first_utime) * 1e-6, sources.size(), converged, static_cast<long>(c.doa_new_sources),
             static_cast<long>(c.sources_pruned), static_cast<long>(c.mirrors_pruned),
             static_cast<long>(c.doa_used), static_cast<long>(c.doa_tentative), static_cast<long>(c.doa_gated_out));
      if (final_report) {
        for (const auto& s : sources) {
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s.covariance.topLeftCorner<2, 2>());
          printf("  source %3ld at (%6.2f, %6.2f, %5.2f) m, std %.2f m, %s, %d DOAs%s\n", static_cast<long>(s.id),
                 s.position_m.x(), s.position_m.y(), s.position_m.z(),
                 std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff())),
                 s.state == OnlineSoundMap::Source::kConverged ? "converged"
                 : s.state == OnlineSoundMap::Source::kSilent  ? "silent"
                                                               : "initialising",
                 s.num_observations, s.is_person ? ", person" : "");
        }
      }
      if (!have_truth) return;
      for (const auto& ts : truth.sources) {
        const Eigen::Vector2d p(ts.position_m[0], ts.position_m[1]);
        double best = std::numeric_limits<double>::infinity(), best_conv = best;
        for (const auto& s : sources) {
          const double d = (s.position_m.head<2>() - p).norm();
          best = std::min(best, d);
          if (s.state != OnlineSoundMap::Source::kInitialising) best_conv = std::min(best_conv, d);
        }
        printf("  truth %-18s (%5.2f, %5.2f): nearest source %.3f m, nearest converged %.3f m\n", ts.name.c_str(),
               p.x(), p.y(), best, best_conv);
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
    report(last, true);
    return 0;
  });
}
