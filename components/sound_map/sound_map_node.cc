// sarmap-sound-map: the CI sound-source map (Su 2017 §4.3) as an LCM node.
//   in:  DOA (doa_t), PEOPLE_AUDIO (people_detections_t), POSE (pose_t), SLAM_ANCHORS
//   out: SLAM_ANCHOR_REQUEST (slam_anchor_request_t), SOUND_MAP (sound_map_t)
// Inputs go through a time-ordered queue; results depend on message time only.
#include <cstdio>
#include <functional>
#include <set>

#include <Eigen/Geometry>

#include "common/node_main.h"
#include "common/logging.h"
#include "common/node.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "common/time.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/slam_anchor_request_t.hpp"
#include "sarmap/slam_anchors_t.hpp"
#include "sarmap/sound_map_t.hpp"
#include "sound_map/online_sound_map.h"

namespace {

using sarmap::common::Utime;
using sarmap::sound_map::OnlineSoundMap;
using sarmap::sound_map::Pose2;

struct SoundMapNodeOptions {
  std::string client_id = "sarmap-sound-map";
  std::string robot_config = "config/robot.yaml";
  std::string doa_channel = "DOA";
  std::string people_audio_channel = "PEOPLE_AUDIO";
  std::string pose_channel = "POSE";
  std::string anchors_channel = "SLAM_ANCHORS";
  std::string anchor_request_channel = "SLAM_ANCHOR_REQUEST";
  std::string sound_map_channel = "SOUND_MAP";
  double reorder_delay_s = 0.3;
  double publish_period_s = 0.5;
  double request_repeat_s = 5.0;
  sarmap::sound_map::OnlineSoundMapOptions map;
  template <class V>
  void Visit(V& v) {
    v("client_id", client_id, "client id in SLAM_ANCHOR_REQUEST");
    v("robot_config", robot_config, "robot description with base_from_mic_array");
    v("doa_channel", doa_channel, "directions of arrival in");
    v("people_audio_channel", people_audio_channel, "heard people in (marks sources as persons)");
    v("pose_channel", pose_channel, "current map_from_base pose in");
    v("anchors_channel", anchors_channel, "SLAM anchors and joint covariance in");
    v("anchor_request_channel", anchor_request_channel, "anchor node requests out");
    v("sound_map_channel", sound_map_channel, "the sound map out");
    v("reorder_delay_s", reorder_delay_s, "inputs are processed in time order once this much newer data arrived");
    v("publish_period_s", publish_period_s, "SOUND_MAP period, message time");
    v("request_repeat_s", request_repeat_s, "re-send the anchor request this often (wall clock; 0: only on change)");
    v("map", map, "sound map estimator");
  }
  void Validate(sarmap::common::Validator& check) const {
    check.NonNegative("reorder_delay_s", reorder_delay_s);
    check.Positive("publish_period_s", publish_period_s);
    check.NonNegative("request_repeat_s", request_repeat_s);
    check.That(!robot_config.empty(), "robot_config", "must name the robot description");
  }
};

// (common/message_conversions.h's FromCovariance6 does not compile when instantiated, so
// the two conversions needed here are local.)
Pose2 PlanarPose(const sarmap::pose_t& msg) {
  const Eigen::Quaterniond q(msg.orientation[0], msg.orientation[1], msg.orientation[2], msg.orientation[3]);
  const Eigen::Vector3d x = q.normalized() * Eigen::Vector3d::UnitX();
  return Pose2(msg.position_m[0], msg.position_m[1], std::atan2(x.y(), x.x()));
}
Eigen::Matrix3d PlanarCovariance(const double (&cov)[36]) {
  const int idx[3] = {0, 1, 5};  // x y yaw of (x y z roll pitch yaw)
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = cov[6 * idx[r] + idx[c]];
  return out;
}

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
        "Channels in: DOA, PEOPLE_AUDIO, POSE, SLAM_ANCHORS. Out: SLAM_ANCHOR_REQUEST, SOUND_MAP.");
    const auto parsed = sarmap::common::ParseNodeOptions<SoundMapNodeOptions>(&parser, &node_args, argc, argv, "config/sound_map.yaml");
    if (!parsed) return 0;
    const SoundMapNodeOptions& options = *parsed;
    const auto robot = sarmap::common::LoadRobot(options.robot_config);
    sarmap::sound_map::ArrayMount mount;
    mount.x_m = robot.base_from_mic_array.x_m;
    mount.y_m = robot.base_from_mic_array.y_m;
    mount.z_m = robot.base_from_mic_array.z_m;
    mount.yaw_rad = robot.base_from_mic_array.yaw_rad;
    if (std::abs(robot.base_from_mic_array.roll_rad) > 1e-6 || std::abs(robot.base_from_mic_array.pitch_rad) > 1e-6) {
      SARMAP_LOG(WARN) << "base_from_mic_array roll/pitch are ignored by the planar sound map";
    }

    OnlineSoundMap map(options.map, mount);
    sarmap::common::Node node("sarmap-sound-map", node_args.lcm_url);
    auto map_pub = node.Advertise<sarmap::sound_map_t>(options.sound_map_channel);
    auto request_pub = node.Advertise<sarmap::slam_anchor_request_t>(options.anchor_request_channel);
    sarmap::common::TimeOrderedQueue<std::function<void(Utime)>> queue(
        sarmap::common::SecondsToUtime(options.reorder_delay_s));
    Utime last_publish = INT64_MIN / 2, newest = 0;
    int64_t warned_kind = 0;

    auto send_request = [&](Utime utime) {
      sarmap::slam_anchor_request_t req;
      req.header.utime = utime;
      req.header.frame = "map";
      req.client_id = options.client_id;
      req.node_ids = map.AnchorNodeIds();
      req.num_node_ids = static_cast<int32_t>(req.node_ids.size());
      request_pub.Publish(&req);
    };
    auto publish_map = [&](Utime utime) {
      sarmap::sound_map_t msg;
      msg.header.utime = utime;
      msg.header.frame = "map";
      for (const auto& s : map.Sources(utime)) {
        sarmap::sound_source_t out;
        out.id = s.id;
        for (int i = 0; i < 3; ++i) out.position_m[i] = s.position_m[i];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) out.covariance[3 * r + c] = s.covariance(r, c);
        out.state = static_cast<int8_t>(s.state);
        out.hypotheses_left = s.hypotheses_left;
        out.is_person = s.is_person;
        out.first_heard_utime = s.first_heard_utime;
        out.last_heard_utime = s.last_heard_utime;
        out.num_observations = s.num_observations;
        msg.sources.push_back(out);
      }
      msg.num_sources = static_cast<int32_t>(msg.sources.size());
      map_pub.Publish(&msg);
      last_publish = utime;
    };
    auto after_input = [&](Utime utime) {
      if (map.TakeAnchorsChanged()) send_request(utime);
      if (utime - last_publish >= sarmap::common::SecondsToUtime(options.publish_period_s)) publish_map(utime);
      const auto& c = map.counters();
      if (c.doa_unsupported_kind > warned_kind) {
        warned_kind = c.doa_unsupported_kind;
        static sarmap::common::RateLimiter limit(10.0);
        if (limit.Allow(sarmap::common::SteadySeconds())) {
          SARMAP_LOG(WARN) << c.doa_unsupported_kind
                           << " DOA(s) of kind ANGLE_1D (linear array cone angle) ignored: the online "
                              "planar map needs azimuth; see README (linear arrays)";
        }
      }
    };
    auto push = [&](Utime utime, std::function<void(Utime)> fn) {
      newest = std::max(newest, utime);
      if (!queue.Push(utime, std::move(fn))) return;
      queue.Release([&](Utime t, std::function<void(Utime)>& f) {
        f(t);
        after_input(t);
      });
    };

    node.Subscribe<sarmap::pose_t>(options.pose_channel, [&](const sarmap::pose_t& msg, const auto&) {
      const Pose2 pose = PlanarPose(msg);
      const Eigen::Matrix3d cov = PlanarCovariance(msg.covariance);
      const int64_t node_id = msg.node_id;
      push(msg.header.utime, [&map, pose, cov, node_id](Utime t) { map.OnPose(t, pose, cov, node_id); });
    });
    node.Subscribe<sarmap::slam_anchors_t>(options.anchors_channel, [&](const sarmap::slam_anchors_t& msg, const auto&) {
      const int n = msg.num_anchors;
      const int dim = msg.covariance_dim;
      if (dim != 3 * (1 + n) || static_cast<int>(msg.covariance.size()) != dim) {
        static sarmap::common::RateLimiter limit(5.0);
        if (limit.Allow(sarmap::common::SteadySeconds())) {
          SARMAP_LOG(WARN) << "SLAM_ANCHORS: covariance_dim " << dim << " != 3(1+" << n << "), dropped";
        }
        return;
      }
      Eigen::MatrixXd cov(dim, dim);
      for (int r = 0; r < dim; ++r) {
        if (static_cast<int>(msg.covariance[r].size()) != dim) return;
        for (int c = 0; c < dim; ++c) cov(r, c) = msg.covariance[r][c];
      }
      const Pose2 current(msg.current.x_m, msg.current.y_m, msg.current.yaw_rad);
      std::vector<std::pair<int64_t, Pose2>> anchors;
      for (const auto& a : msg.anchors) anchors.emplace_back(a.node_id, Pose2(a.x_m, a.y_m, a.yaw_rad));
      push(msg.header.utime, [&map, current, anchors, cov](Utime t) {
        if (!map.OnSlamAnchors(t, current, anchors, cov)) {
          static sarmap::common::RateLimiter limit(5.0);
          if (limit.Allow(sarmap::common::SteadySeconds())) {
            SARMAP_LOG(WARN) << "SLAM_ANCHORS rejected (non-finite covariance)";
          }
        }
      });
    });
    node.Subscribe<sarmap::doa_t>(options.doa_channel, [&](const sarmap::doa_t& msg, const auto&) {
      std::vector<OnlineSoundMap::Doa> doas;
      for (const auto& s : msg.sources) {
        OnlineSoundMap::Doa d;
        d.track_id = s.track_id;
        d.kind = s.kind;
        d.azimuth_rad = s.azimuth_rad;
        d.elevation_rad = s.elevation_rad;
        d.covariance << s.covariance[0], s.covariance[1], s.covariance[2], s.covariance[3];
        if (!std::isfinite(d.azimuth_rad) || !d.covariance.allFinite()) continue;
        doas.push_back(d);
      }
      const std::string device = msg.device_id;
      push(msg.header.utime, [&map, device, doas](Utime t) { map.OnDoa(t, device, doas); });
    });
    node.Subscribe<sarmap::people_detections_t>(
        options.people_audio_channel, [&](const sarmap::people_detections_t& msg, const auto&) {
          std::vector<int64_t> tracks;
          for (const auto& d : msg.detections)
            if (d.cue == sarmap::person_detection_t::CUE_HEARD && d.track_id >= 0) tracks.push_back(d.track_id);
          const std::string device = msg.sensor_id;
          push(msg.header.utime, [&map, device, tracks](Utime) {
            for (int64_t t : tracks) map.OnHeardPerson(device, t);
          });
        });
    if (options.request_repeat_s > 0)
      node.AddTimer(options.request_repeat_s, [&] {
        if (!map.AnchorNodeIds().empty()) send_request(newest);
      });
    node.AddTimer(1.0, [&] {
      const auto& c = map.counters();
      node.SetStatusMessage("sources " + std::to_string(map.ekf().source_ids().size()) + ", doa used " +
                            std::to_string(c.doa_used) + ", gated " + std::to_string(c.doa_gated_out) +
                            ", back-propagations " + std::to_string(c.back_propagations) + ", late inputs " +
                            std::to_string(queue.dropped_late()));
    });
    return node.Run();
  });
}
