// sarmap-people-map: PEOPLE_VISUAL, PEOPLE_AUDIO, SOUND_MAP and POSE in; PEOPLE_MAP out.
// Inputs pass through a time-ordered queue and are applied in capture-time order with the
// robot pose interpolated at each detection's capture time, so replaying a log gives the same
// people map every time. The state is saved crash-safe and resumed after a restart.
#include <cstdio>

#include "common/node.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "common/state_file.h"
#include "people_map/people_map.h"
#include "people_map/people_map_intake.h"

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-people-map", [&] {
    using namespace sarmap;
    using common::Utime;
    common::ArgParser parser(
        "sarmap-people-map",
        "The people map: moves each person seen or heard into the map frame with the robot pose\n"
        "at the detection's capture time, merges detections within 45 cm, fuses a heard person\n"
        "with a seen one, places heard-only people at their sound-map position, and keeps a\n"
        "confidence that grows with evidence and decays without it.\n"
        "In: PEOPLE_VISUAL, PEOPLE_AUDIO, SOUND_MAP, POSE.  Out: PEOPLE_MAP.");
    common::NodeArgs args;
    const auto parsed = common::ParseNodeOptions<people_map::PeopleMapNodeOptions>(
        &parser, &args, argc, argv, "config/people_map.yaml");
    if (!parsed) return 0;
    const people_map::PeopleMapNodeOptions& options = *parsed;
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

    common::Node node("sarmap-people-map", args);
    auto publisher = node.Advertise<people_map_t>(options.output_channel);
    // One far-future stamp must not move the pose history or the queue's clock: each input
    // stream is gated on its own clock (common/stamp_gate.h).
    constexpr int kPoseGate = 0, kSeenGate = 1, kHeardGate = 2, kSoundMapGate = 3;
    common::StampGates gates(options.stamp_gate);
    const auto stamp_ok = [&](int gate, Utime utime, const common::ReceiveInfo& info) {
      if (gates.Accept(gate, utime, info.receive_time_s)) return true;
      node.Reject(info.channel, "stamp " + std::to_string(utime) + " far from the stream's clock");
      return false;
    };
    const auto publish = [&](Utime utime) {
      auto msg = people_map::PeopleMapMessage(map.Report(utime), utime);
      publisher.Publish(&msg);
    };
    people_map::PeopleMapIntake intake(options, base_from_camera, base_from_mic, &map, publish);
    // After a restart from saved state, the people already found are published at once (at the
    // time of their last detection), not only after the next detection: the operator and the
    // recorder never see the map lose them.
    Utime latest_utime = 0;
    for (const auto& [id, person] : map.people())
      latest_utime = std::max(latest_utime, person.last_detected_utime);
    intake.set_latest_utime(latest_utime);

    node.Subscribe<pose_t>(options.pose_channel, [&](const pose_t& m, const auto& info) {
      if (stamp_ok(kPoseGate, m.header.utime, info)) intake.OnPose(m);
    });
    node.Subscribe<people_detections_t>(options.visual_channel,
                                        [&](const people_detections_t& m, const auto& info) {
                                          if (stamp_ok(kSeenGate, m.header.utime, info))
                                            intake.OnSeen(m);
                                        });
    node.Subscribe<people_detections_t>(options.audio_channel,
                                        [&](const people_detections_t& m, const auto& info) {
                                          if (stamp_ok(kHeardGate, m.header.utime, info))
                                            intake.OnHeard(m);
                                        });
    node.Subscribe<sound_map_t>(options.sound_map_channel,
                                [&](const sound_map_t& m, const auto& info) {
                                  if (stamp_ok(kSoundMapGate, m.header.utime, info))
                                    intake.OnSoundMap(m);
                                });

    node.AddTimer(options.publish_period_s, [&] {
      intake.Release();
      if (intake.latest_utime() > 0) publish(intake.latest_utime());
      node.SetStatusMessage(std::to_string(map.people().size()) + " people, " +
                            std::to_string(intake.without_pose()) + " detections without pose, " +
                            std::to_string(intake.dropped_late()) + " late, " +
                            std::to_string(gates.dropped()) + " off-clock stamps (" +
                            std::to_string(gates.reanchors()) + " re-anchors)");
    });
    const auto save = [&] {
      if (options.state_file.empty() || !intake.dirty()) return;
      try {
        map.Save(options.state_file);
        intake.clear_dirty();
      } catch (const std::exception& e) {
        SARMAP_LOG(ERROR) << common::EscapeForLog(e.what(), 512);  // may quote a keyword
      }
    };
    node.AddTimer(options.save_period_s, save);
    const int code = node.Run();
    intake.Finish();
    if (intake.latest_utime() > 0) publish(intake.latest_utime());
    save();
    return code;
  });
}
