// sarmap-people-map: PEOPLE_VISUAL, PEOPLE_AUDIO, SOUND_MAP and POSE in; PEOPLE_MAP out.
// Inputs pass through a time-ordered queue and are applied in capture-time order with the
// robot pose interpolated at each detection's capture time, so replaying a log gives the same
// people map every time. The state is saved crash-safe and resumed after a restart.
#include <cstdio>
#include <deque>
#include <functional>

#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/pose_history.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "common/state_file.h"
#include "people_map/people_map.h"
#include "sarmap/doa_source_t.hpp"

namespace {

using sarmap::common::Utime;

struct NodeOptions {
  std::string robot_config = "config/robot.yaml";
  std::string state_file = "";  // "" = no persistence
  double save_period_s = 1.0;
  double publish_period_s = 1.0;
  double reorder_delay_s = 0.5;  // inputs are held this long to be applied in time order
  double max_pose_gap_s = 0.5;
  // A detection newer than the latest pose waits for a pose at or after its time (to be placed
  // between two poses, not with the last one): SLAM publishes late while it optimises, and a
  // pose 0.3 s old in a 35 deg/s turn puts a person 3.5 m away 0.6 m off. If none comes within
  // this long (the newest input's time), or the node stops first, it is dropped and counted.
  double pose_wait_s = 2.0;
  std::string visual_channel = "PEOPLE_VISUAL";
  std::string audio_channel = "PEOPLE_AUDIO";
  std::string sound_map_channel = "SOUND_MAP";
  std::string pose_channel = "POSE";
  std::string output_channel = "PEOPLE_MAP";
  sarmap::common::StampGateOptions stamp_gate;
  sarmap::people_map::PeopleMapOptions map;
  template <class V>
  void Visit(V& v) {
    v("robot_config", robot_config, "robot extrinsics YAML (camera and array on the base)");
    v("state_file", state_file, "where the people map is saved and resumed from (\"\": nowhere)");
    v("save_period_s", save_period_s, "seconds between state saves (when changed)");
    v("publish_period_s", publish_period_s, "PEOPLE_MAP is also republished this often");
    v("reorder_delay_s", reorder_delay_s, "inputs wait this long to be applied in capture-time order");
    v("max_pose_gap_s", max_pose_gap_s, "largest gap to a known pose accepted for a detection");
    v("pose_wait_s", pose_wait_s,
      "a detection newer than the latest pose waits this long (message time) for a later pose to "
      "interpolate from, else it is dropped (never placed with an extrapolated pose)");
    v("visual_channel", visual_channel, "people seen");
    v("audio_channel", audio_channel, "people heard");
    v("sound_map_channel", sound_map_channel, "sound-source map");
    v("pose_channel", pose_channel, "robot pose in the map");
    v("output_channel", output_channel, "the people map");
    v("stamp_gate", stamp_gate,
      "inputs stamped far from their stream's clock are dropped and counted, never adopted");
    v("map", map, "people map");
  }
  void Validate(sarmap::common::Validator& check) const {
    check.Positive("save_period_s", save_period_s);
    check.Positive("publish_period_s", publish_period_s);
    check.NonNegative("reorder_delay_s", reorder_delay_s);
    check.Positive("max_pose_gap_s", max_pose_gap_s);
    check.NonNegative("pose_wait_s", pose_wait_s);
  }
};

sarmap::people_map_t ToMessage(const std::vector<sarmap::people_map::Person>& people, Utime utime) {
  sarmap::people_map_t msg;
  msg.header.utime = utime;
  msg.header.frame = "map";
  for (const auto& p : people) {
    sarmap::mapped_person_t m;
    m.id = p.id;
    for (int i = 0; i < 3; ++i) m.position_m[i] = p.position_m[i];
    for (int i = 0; i < 9; ++i) m.covariance[i] = p.covariance(i / 3, i % 3);
    m.confidence = static_cast<float>(p.confidence);
    m.cues = static_cast<int8_t>(p.cues);
    m.num_detections = p.num_detections;
    m.people_count = p.people_count;
    m.first_detected_utime = p.first_detected_utime;
    m.last_detected_utime = p.last_detected_utime;
    m.keyword = p.keyword;
    m.sound_source_id = p.sound_source_id;
    msg.people.push_back(m);
  }
  msg.num_people = static_cast<int32_t>(msg.people.size());
  return msg;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-people-map", [&] {
    using namespace sarmap;
    common::ArgParser parser(
        "sarmap-people-map",
        "The people map: moves each person seen or heard into the map frame with the robot pose\n"
        "at the detection's capture time, merges detections within 45 cm, fuses a heard person\n"
        "with a seen one, places heard-only people at their sound-map position, and keeps a\n"
        "confidence that grows with evidence and decays without it.\n"
        "In: PEOPLE_VISUAL, PEOPLE_AUDIO, SOUND_MAP, POSE.  Out: PEOPLE_MAP.");
    common::NodeArgs args;
    const auto parsed = common::ParseNodeOptions<NodeOptions>(&parser, &args, argc, argv, "config/people_map.yaml");
    if (!parsed) return 0;
    const NodeOptions& options = *parsed;
    const common::RobotOptions robot = common::LoadRobot(options.robot_config);
    const common::Rigid3d base_from_camera = robot.base_from_camera.ToRigid3d();
    const common::Rigid3d base_from_mic = robot.base_from_mic_array.ToRigid3d();

    people_map::PeopleMap map(options.map);
    if (!options.state_file.empty()) {
      // A corrupt state file must not make the node crash-loop: one clear line, a clean start.
      try {
        if (map.Load(options.state_file)) {
          SARMAP_LOG(INFO) << "resumed " << map.people().size() << " people from "
                           << options.state_file;
        }
      } catch (const std::exception& e) {
        const std::string aside = common::SetAsideStateFile(options.state_file);
        SARMAP_LOG(ERROR) << "not resumed, starting with an empty people map: "
                          << common::EscapeForLog(e.what(), 512)
                          << (aside.empty() ? "" : " (moved to " + aside + ")");
      }
    }

    common::Node node("sarmap-people-map", args.lcm_url);
    auto publisher = node.Advertise<people_map_t>(options.output_channel);
    common::PoseHistory poses(common::SecondsToUtime(60.0), common::SecondsToUtime(options.max_pose_gap_s));
    // Each input is ordered within its own stream: a keyword is published only after its
    // utterance has been decoded (0.1-2 s after it was said), later than the visual detections
    // of the same instant, and must not be dropped as late.
    common::TimeOrderedQueue<std::function<void()>> queue(common::SecondsToUtime(options.reorder_delay_s));
    constexpr int kHeardStream = 1, kSoundMapStream = 2;
    // One far-future stamp must not move the pose history or the queue's clock: each input
    // stream is gated on its own clock (common/stamp_gate.h).
    constexpr int kPoseGate = 0, kSeenGate = 1, kHeardGate = 2, kSoundMapGate = 3;
    common::StampGates gates(options.stamp_gate);
    const auto stamp_ok = [&](int gate, Utime utime, const common::ReceiveInfo& info) {
      if (gates.Accept(gate, utime, info.receive_time_s)) return true;
      node.Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
      return false;
    };
    // After a restart from saved state, the people already found are published at once (at the
    // time of their last detection), not only after the next detection: the operator and the
    // recorder never see the map lose them.
    Utime latest_utime = 0;
    for (const auto& [id, person] : map.people()) latest_utime = std::max(latest_utime, person.last_detected_utime);
    bool dirty = false;
    int64_t without_pose = 0;

    const auto publish = [&](Utime utime) {
      auto msg = ToMessage(map.Report(utime), utime);
      publisher.Publish(&msg);
    };
    // An input at `utime` changed the map.
    const auto applied = [&](Utime utime) {
      latest_utime = std::max(latest_utime, utime);
      dirty = true;
    };
    const auto pose_at = [&](Utime utime) -> std::optional<common::StampedPose> {
      auto pose = poses.At(utime);
      if (!pose) {
        ++without_pose;
        SARMAP_LOG(WARN) << "no robot pose within " << options.max_pose_gap_s << " s of a detection at "
                         << utime << "; dropped (" << without_pose << " so far)";
      }
      return pose;
    };
    // Detections released from the queue before a pose at or after their time arrived, oldest
    // first: placed as soon as POSE catches up, or after pose_wait_s.
    std::deque<std::pair<Utime, std::function<void()>>> waiting_for_pose;
    Utime newest_input_utime = INT64_MIN;
    const Utime pose_wait_us = common::SecondsToUtime(options.pose_wait_s);
    // final: the node stops, no pose will come.
    const auto place_waiting = [&](bool final) {
      while (!waiting_for_pose.empty()) {
        const Utime utime = waiting_for_pose.front().first;
        if (utime > poses.newest_utime()) {
          if (!final && newest_input_utime - utime <= pose_wait_us) break;
          // Never placed with a pose extrapolated into a turn: dropped and counted.
          ++without_pose;
          waiting_for_pose.pop_front();
          continue;
        }
        waiting_for_pose.front().second();
        waiting_for_pose.pop_front();
        applied(utime);
        publish(latest_utime);
      }
    };
    // Runs `place` (which looks up the pose at `utime`) now if a pose at or after `utime` is
    // known and nothing older waits, else queues it.
    const auto when_posed = [&](Utime utime, std::function<void()> place) {
      if (waiting_for_pose.empty() && poses.newest_utime() >= utime) {
        place();
        return;
      }
      waiting_for_pose.emplace_back(utime, std::move(place));
    };
    const auto release = [&] {
      queue.Release([&](Utime utime, std::function<void()>& apply) {
        apply();
        applied(utime);
        publish(latest_utime);
      });
      place_waiting(false);
    };

    node.Subscribe<pose_t>(options.pose_channel, [&](const pose_t& m, const auto& info) {
      if (!stamp_ok(kPoseGate, m.header.utime, info)) return;
      common::StampedPose p;
      p.utime = m.header.utime;
      p.pose = common::ToRigid3d(m.position_m, m.orientation);
      p.covariance = common::ToCovariance6(m.covariance);
      poses.Add(p);
      newest_input_utime = std::max(newest_input_utime, p.utime);
      // POSE is the one input that never stops (detections do when nobody is in view; the sound
      // map publishes 3 s late): it moves the queue's clock.
      queue.AdvanceTo(p.utime);
      release();
    });
    node.Subscribe<people_detections_t>(options.visual_channel, [&](const people_detections_t& m,
                                                                    const auto& info) {
      const Utime utime = m.header.utime;
      if (!stamp_ok(kSeenGate, utime, info)) return;
      std::vector<people_map::SeenDetection> seen;
      for (const auto& d : m.detections) {
        if (!d.has_range || d.cue == person_detection_t::CUE_HEARD) continue;
        people_map::SeenDetection s;
        s.position_camera_m = Eigen::Vector3d(d.position_m[0], d.position_m[1], d.position_m[2]);
        s.covariance_camera = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.position_covariance);
        s.confidence = d.confidence;
        s.cue = d.cue == person_detection_t::CUE_SEEN_DEPTH ? people_map::kSeenDepth : people_map::kSeenRgbd;
        seen.push_back(s);
      }
      if (seen.empty()) return;
      newest_input_utime = std::max(newest_input_utime, utime);
      queue.Push(utime, [&, utime, seen] {
        when_posed(utime, [&, utime, seen] {
          if (auto pose = pose_at(utime)) {
            const Eigen::Matrix3d planar = common::PlanarCovariance(pose->covariance);
            map.AddSeen(utime, seen, pose->pose * base_from_camera, planar,
                        pose->pose.translation().head<2>());
          }
        });
      });
      release();
    });
    node.Subscribe<people_detections_t>(options.audio_channel, [&](const people_detections_t& m,
                                                                   const auto& info) {
      const Utime utime = m.header.utime;
      if (!stamp_ok(kHeardGate, utime, info)) return;
      std::vector<people_map::HeardDetection> heard;
      for (const auto& d : m.detections) {
        people_map::HeardDetection h;
        h.azimuth_rad = d.azimuth_rad;
        h.elevation_rad = d.elevation_rad;
        h.azimuth_sigma_rad = std::sqrt(std::max(0.0, d.direction_covariance[0]));
        h.confidence = d.confidence;
        h.keyword = d.keyword;
        heard.push_back(h);
      }
      if (heard.empty()) return;
      newest_input_utime = std::max(newest_input_utime, utime);
      queue.Push(
          utime,
          [&, utime, heard] {
            when_posed(utime, [&, utime, heard] {
              if (auto pose = pose_at(utime))
                map.AddHeard(utime, heard, pose->pose * base_from_mic);
            });
          },
          kHeardStream);
      release();
    });
    node.Subscribe<sound_map_t>(options.sound_map_channel, [&](const sound_map_t& m,
                                                               const auto& info) {
      if (!stamp_ok(kSoundMapGate, m.header.utime, info)) return;
      std::vector<people_map::SoundSource> sources;
      for (const auto& s : m.sources) {
        // Only placed voices can be people: a bearing has no position yet, and a machine or
        // an alarm is never a person, whatever the keyword spotter heard near it.
        if (!s.has_position || s.sound_class != doa_source_t::SOUND_CLASS_VOICE) continue;
        people_map::SoundSource src;
        src.id = s.id;
        src.position_m = Eigen::Vector3d(s.position_m[0], s.position_m[1], s.position_m[2]);
        src.covariance = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(s.covariance);
        src.is_person = s.is_person;
        src.converged = s.state == sound_source_t::STATE_CONVERGED;
        sources.push_back(src);
      }
      const Utime utime = m.header.utime;
      queue.Push(utime, [&, utime, sources] { map.UpdateSoundSources(utime, sources); }, kSoundMapStream);
      release();
    });

    node.AddTimer(options.publish_period_s, [&] {
      release();
      if (latest_utime > 0) publish(latest_utime);
      node.SetStatusMessage(std::to_string(map.people().size()) + " people, " +
                            std::to_string(without_pose) + " detections without pose, " +
                            std::to_string(queue.dropped_late()) + " late, " +
                            std::to_string(gates.dropped()) + " off-clock stamps (" +
                            std::to_string(gates.reanchors()) + " re-anchors)");
    });
    const auto save = [&] {
      if (options.state_file.empty() || !dirty) return;
      try {
        map.Save(options.state_file);
        dirty = false;
      } catch (const std::exception& e) {
        SARMAP_LOG(ERROR) << common::EscapeForLog(e.what(), 512);  // may quote a keyword
      }
    };
    node.AddTimer(options.save_period_s, save);
    const int code = node.Run();
    queue.Flush([&](Utime utime, std::function<void()>& apply) {
      apply();
      applied(utime);
    });
    place_waiting(true);
    if (latest_utime > 0) publish(latest_utime);
    save();
    return code;
  });
}
