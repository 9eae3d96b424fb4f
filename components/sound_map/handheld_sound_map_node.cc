// sarmap-handheld-sound-map: the linear-array sound map of Su 2017 ch. 5 as an LCM node, for a
// hand-held rig whose 6-DoF pose comes from RGB-D odometry (sarmap-rgbd-odometry).
//   in:  RIG_POSE (pose_t), DOA_MAP (doa_t, KIND_ANGLE_1D), PEOPLE_AUDIO (people_detections_t)
//   out: SOUND_MAP (sound_map_t)
// Inputs go through a time-ordered queue; results depend on message time only.
#include <Eigen/Geometry>
#include <cstdio>
#include <functional>

#include "common/logging.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/options.h"
#include "common/stamp_gate.h"
#include "common/time.h"
#include "sound_map/handheld_sound_map_messages.h"
#include "sound_map/linear_array_map.h"

namespace {
using sarmap::common::Utime;
using sarmap::sound_map::HandheldSoundMapOptions;
using sarmap::sound_map::LinearArraySoundMap;
}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-handheld-sound-map", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-handheld-sound-map",
        "Maps stationary sound sources heard by a linear microphone array (a Kinect's) on a\n"
        "hand-held RGB-D rig (Su 2017 ch. 5): each new source starts as N_h hypotheses on the\n"
        "cone of its first DOA, pruned by chi-square and converged by linearity index; converged\n"
        "sources are refined jointly with the last keyframe poses of the rig's odometry.");
    sarmap::common::NodeArgs node_args;
    parser.SetEpilog(
        "Channels in: RIG_POSE (sarmap-rgbd-odometry), DOA_MAP (sarmap-sound-localisation with a\n"
        "linear array), PEOPLE_AUDIO. Out: SOUND_MAP, positions in the odometry's frame (the rig "
        "at\n"
        "its first frame) as corrected by the joint optimisation.");
    const auto parsed = sarmap::common::ParseNodeOptions<HandheldSoundMapOptions>(
        &parser, &node_args, argc, argv, "config/handheld_sound_map.yaml");
    if (!parsed) return 0;
    const HandheldSoundMapOptions& options = *parsed;
    const Eigen::Isometry3d rig_from_sensor =
        sarmap::sound_map::RigFromSensor(options.rig_from_mic_array);

    LinearArraySoundMap map(options.map);
    sarmap::common::Node node("sarmap-handheld-sound-map", node_args);
    auto map_pub = node.Advertise<sarmap::sound_map_t>(options.sound_map_channel);
    sarmap::common::TimeOrderedQueue<std::function<void(Utime)>> queue(
        sarmap::common::SecondsToUtime(options.reorder_delay_s));
    Utime last_publish = INT64_MIN / 2, newest = 0;
    int64_t bad_poses = 0, other_kinds = 0, warned_kinds = 0;

    auto publish_map = [&](Utime utime) {
      sarmap::sound_map_t msg = sarmap::sound_map::LinearSoundMapMessage(map, utime);
      map_pub.Publish(&msg);
      last_publish = utime;
    };
    const auto apply = [&](Utime t, std::function<void(Utime)>& f) {
      f(t);
      if (t - last_publish >= sarmap::common::SecondsToUtime(options.publish_period_s))
        publish_map(t);
    };
    // One far-future stamp must not become the queue's clock (every later input "late"): each
    // input stream is gated on its own clock (common/stamp_gate.h).
    enum Gate { kPoseGate, kDoaGate, kHeardGate };
    sarmap::common::StampGates gates(options.stamp_gate);
    const auto stamp_ok = [&](Gate gate, Utime utime, const sarmap::common::ReceiveInfo& info) {
      if (gates.Accept(gate, utime, info.receive_time_s)) return true;
      node.Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
      return false;
    };
    auto push = [&](Utime utime, std::function<void(Utime)> fn) {
      newest = std::max(newest, utime);
      if (!queue.Push(utime, std::move(fn))) return;
      queue.Release(apply);
    };

    node.Subscribe<sarmap::pose_t>(
        options.pose_channel, [&](const sarmap::pose_t& msg, const auto& info) {
          if (!stamp_ok(kPoseGate, msg.header.utime, info)) return;
          Eigen::Isometry3d odom_from_rig;
          if (!sarmap::sound_map::IsometryFromPose(msg, &odom_from_rig)) {
            ++bad_poses;
            static sarmap::common::RateLimiter limit(10.0);
            if (limit.Allow(sarmap::common::SteadySeconds()))
              SARMAP_LOG(WARN) << options.pose_channel
                               << ": non-finite position or non-unit quaternion, dropped ("
                               << bad_poses << " so far)";
            return;
          }
          const Eigen::Isometry3d odom_from_sensor = odom_from_rig * rig_from_sensor;
          push(msg.header.utime,
               [&map, odom_from_sensor](Utime t) { map.OnPose(t, odom_from_sensor); });
        });
    node.Subscribe<sarmap::doa_t>(options.doa_channel, [&](const sarmap::doa_t& msg,
                                                           const auto& info) {
      if (!stamp_ok(kDoaGate, msg.header.utime, info)) return;
      auto doas = sarmap::sound_map::LinearDoasFromMessage(msg, &other_kinds);
      if (other_kinds > warned_kinds) {
        warned_kinds = other_kinds;
        static sarmap::common::RateLimiter limit(10.0);
        if (limit.Allow(sarmap::common::SteadySeconds()))
          SARMAP_LOG(WARN) << other_kinds
                           << " DOA(s) not KIND_ANGLE_1D ignored: this map needs a linear array's "
                              "cone angles (sarmap-sound-localisation with a linear array)";
      }
      push(msg.header.utime, [&map, doas](Utime t) { map.OnDoa(t, doas); });
    });
    node.Subscribe<sarmap::people_detections_t>(
        options.people_audio_channel,
        [&](const sarmap::people_detections_t& msg, const auto& info) {
          if (!stamp_ok(kHeardGate, msg.header.utime, info)) return;
          const auto heard = sarmap::sound_map::HeardLinearDirections(msg);
          push(msg.header.utime, [&map, heard](Utime t) {
            for (const auto& d : heard) map.OnHeardDirection(t, d);
          });
        });
    node.AddTimer(1.0, [&] {
      const auto& c = map.counters();
      int converged = 0;
      const auto sources = map.sources();
      for (const auto& s : sources) converged += s.converged;
      node.SetStatusMessage(
          "sources " + std::to_string(sources.size()) + " (" + std::to_string(converged) +
          " converged, born " + std::to_string(c.sources_born) + ", merged " +
          std::to_string(c.sources_merged) + ", pruned " + std::to_string(c.sources_pruned) +
          "), keyframes " + std::to_string(c.keyframes) + ", doa used " +
          std::to_string(c.doas_used) + " of " + std::to_string(c.doas) + " (no pose " +
          std::to_string(c.doas_without_pose) + ", gated out " + std::to_string(c.doas_gated_out) +
          "), bad poses " + std::to_string(bad_poses) + ", late inputs " +
          std::to_string(queue.dropped_late()) + ", off-clock stamps " +
          std::to_string(gates.dropped()) + " (re-anchors " + std::to_string(gates.reanchors()) +
          ")");
    });
    const int code = node.Run();
    // The last reorder_delay_s of inputs, then one optimisation over everything, and the final map.
    queue.Flush(apply);
    map.Finish();
    if (newest > 0) publish_map(newest);
    return code;
  });
}
