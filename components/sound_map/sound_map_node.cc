// sarmap-sound-map: the CI sound-source map (Su 2017 §4.3) as an LCM node.
//   in:  DOA_MAP (doa_t, doa_channel), PEOPLE_AUDIO (people_detections_t), POSE (pose_t),
//   SLAM_ANCHORS,
//        MAP (occupancy_grid_t: the mapped site)
//   out: SLAM_ANCHOR_REQUEST (slam_anchor_request_t), SOUND_MAP (sound_map_t)
// Inputs go through a time-ordered queue; results depend on message time only.
#include <Eigen/Geometry>
#include <cstdio>
#include <functional>
#include <set>

#include "common/logging.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "common/state_file.h"
#include "common/time.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/occupancy_grid_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "sound_map/online_sound_map.h"
#include "sound_map/sound_map_intake.h"
#include "sound_map/sound_map_messages.h"

namespace {
using sarmap::common::Utime;
using sarmap::sound_map::OnlineSoundMap;
using sarmap::sound_map::Pose2;
using sarmap::sound_map::SoundMapNodeOptions;
}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-sound-map", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-sound-map",
        "Maps stationary sound sources from DOA observations: an inverse-depth EKF sound map\n"
        "kept conditionally independent of SLAM (Su 2017 §4.3), updated from SLAM_ANCHORS by\n"
        "back-propagation after every SLAM optimisation.");
    sarmap::common::NodeArgs node_args;
    parser.SetEpilog(
        "Channels in: DOA, PEOPLE_AUDIO, POSE, SLAM_ANCHORS, MAP. Out: SLAM_ANCHOR_REQUEST, "
        "SOUND_MAP.");
    const auto parsed = sarmap::common::ParseNodeOptions<SoundMapNodeOptions>(
        &parser, &node_args, argc, argv, "config/sound_map.yaml");
    if (!parsed) return 0;
    const SoundMapNodeOptions& options = *parsed;
    const auto robot = sarmap::common::LoadRobot(options.robot_config);
    const sarmap::sound_map::ArrayMount mount = sarmap::sound_map::MountFromRobot(robot);
    if (std::abs(robot.base_from_mic_array.roll_rad) > 1e-6 ||
        std::abs(robot.base_from_mic_array.pitch_rad) > 1e-6) {
      SARMAP_LOG(WARN) << "base_from_mic_array roll/pitch are ignored by the planar sound map";
    }

    OnlineSoundMap map(options.map, mount);
    if (options.resume && !options.state_file.empty()) {
      try {
        if (map.Load(options.state_file)) {
          SARMAP_LOG(INFO) << "resumed " << map.ekf().source_ids().size() << " sources from "
                           << options.state_file;
        }
      } catch (const std::exception& e) {  // one clear line and a clean start, no crash loop
        const std::string aside = sarmap::common::SetAsideStateFile(options.state_file);
        SARMAP_LOG(ERROR) << "not resumed, starting empty: "
                          << sarmap::common::EscapeForLog(e.what(), 512)
                          << (aside.empty() ? "" : " (moved to " + aside + ")");
      }
    }
    sarmap::common::Node node("sarmap-sound-map", node_args);
    auto map_pub = node.Advertise<sarmap::sound_map_t>(options.sound_map_channel);
    auto request_pub =
        node.Advertise<sarmap::slam_anchor_request_t>(options.anchor_request_channel);
    sarmap::sound_map::SoundMapIntake intake(
        options, &map, [&](sarmap::sound_map_t& m) { map_pub.Publish(&m); },
        [&](sarmap::slam_anchor_request_t& r) { request_pub.Publish(&r); });
    // One far-future stamp must not become the queue's clock (every later input "late"): each
    // input stream is gated on its own clock (common/stamp_gate.h).
    enum Gate { kPoseGate, kAnchorsGate, kDoaGate, kHeardGate };
    sarmap::common::StampGates gates(options.stamp_gate);
    const auto stamp_ok = [&](Gate gate, Utime utime, const sarmap::common::ReceiveInfo& info) {
      if (gates.Accept(gate, utime, info.receive_time_s)) return true;
      node.Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
      return false;
    };
    node.Subscribe<sarmap::pose_t>(options.pose_channel,
                                   [&](const sarmap::pose_t& msg, const auto& info) {
                                     if (stamp_ok(kPoseGate, msg.header.utime, info))
                                       intake.OnPose(msg);
                                   });
    node.Subscribe<sarmap::slam_anchors_t>(
        options.anchors_channel, [&](const sarmap::slam_anchors_t& msg, const auto& info) {
          if (!stamp_ok(kAnchorsGate, msg.header.utime, info)) return;
          if (!intake.OnAnchors(msg)) {
            static sarmap::common::RateLimiter limit(5.0);
            if (limit.Allow(sarmap::common::SteadySeconds())) {
              SARMAP_LOG(WARN) << "SLAM_ANCHORS: covariance_dim " << msg.covariance_dim
                               << " != 3(1+" << msg.num_anchors << ") or rows missing, dropped";
            }
          }
        });
    node.Subscribe<sarmap::doa_t>(options.doa_channel,
                                  [&](const sarmap::doa_t& msg, const auto& info) {
                                    if (stamp_ok(kDoaGate, msg.header.utime, info))
                                      intake.OnDoa(msg);
                                  });
    node.Subscribe<sarmap::people_detections_t>(
        options.people_audio_channel,
        [&](const sarmap::people_detections_t& msg, const auto& info) {
          if (stamp_ok(kHeardGate, msg.header.utime, info)) intake.OnHeard(msg);
        });
    if (!options.site_map_channel.empty())
      node.Subscribe<sarmap::occupancy_grid_t>(
          options.site_map_channel,
          [&](const sarmap::occupancy_grid_t& msg, const auto&) { intake.OnSiteMap(msg); });
    if (options.request_repeat_s > 0)
      node.AddTimer(options.request_repeat_s, [&] {
        if (!map.AnchorNodeIds().empty()) intake.SendRequest(intake.newest_utime());
      });
    const auto save_state = [&] {
      if (options.state_file.empty() || !intake.changed()) return;
      intake.clear_changed();
      try {
        map.Save(options.state_file);
      } catch (const std::exception& e) {
        static sarmap::common::RateLimiter limit(30.0);
        if (limit.Allow(sarmap::common::SteadySeconds()))
          SARMAP_LOG(WARN) << "state not saved: " << sarmap::common::EscapeForLog(e.what(), 512);
      }
    };
    if (!options.state_file.empty()) node.AddTimer(options.state_save_period_s, save_state);
    node.AddTimer(1.0, [&] {
      const auto& c = map.counters();
      node.SetStatusMessage("sources " + std::to_string(map.ekf().source_ids().size()) + " (born " +
                            std::to_string(c.doa_new_sources) + ", pruned " +
                            std::to_string(c.sources_pruned + c.mirrors_pruned) + "), doa used " +
                            std::to_string(c.doa_used) + ", gated " +
                            std::to_string(c.doa_gated_out) + ", too steep " +
                            std::to_string(c.doa_too_steep) + ", on path " +
                            std::to_string(c.sources_on_path) + ", back-propagations " +
                            std::to_string(c.back_propagations) + " (anchors skipped " +
                            std::to_string(c.anchors_skipped) + "), late inputs " +
                            std::to_string(intake.dropped_late()) + ", off-clock stamps " +
                            std::to_string(gates.dropped()) + " (re-anchors " +
                            std::to_string(gates.reanchors()) + ")");
    });
    const int code = node.Run();
    // What still waits in the queue (the last reorder_delay_s of the mission) is applied, and the
    // final map published and saved.
    intake.Finish();
    save_state();
    return code;
  });
}
