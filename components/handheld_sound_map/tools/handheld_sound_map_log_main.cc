// sarmap-log-handheld-sound-map: replays a hand-held rig's log (RIG_POSE from
// sarmap-rgbd-odometry, a linear array's DOA_MAP, PEOPLE_AUDIO) through
// sarmap-handheld-sound-map's adapter (HandheldSoundMapNode: stamp gates, reorder queue,
// LinearArraySoundMap) on the log's clock (logtools::NodeReplay), and, when the log
// holds SIM_TRUTH, prints each true source's error against its nearest mapped source (and the
// logged SOUND_MAP's), and the rig odometry's drift.
//
//   sarmap-log handheld-sound-map run.lcmlog
//   sarmap-log handheld-sound-map run.lcmlog --truth-poses      # the map from the true rig poses
//   sarmap-log handheld-sound-map run.lcmlog --set map.num_hypotheses=5
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/args.h"
#include "common/decode.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "common/transform.h"
#include "handheld_sound_map/handheld_sound_map_messages.h"
#include "handheld_sound_map/handheld_sound_map_node.h"
#include "log-tools/node_replay.h"
#include "sarmap/sim_truth_t.hpp"

namespace {

using sarmap::sound_map::LinearArraySoundMap;

double Yaw(const Eigen::Isometry3d& m) {
  const Eigen::Vector3d x = m.linear().col(0);
  return std::atan2(x.y(), x.x());
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-handheld-sound-map", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log-handheld-sound-map",
        "Replays RIG_POSE, DOA_MAP and PEOPLE_AUDIO from an LCM log through the hand-held rig's\n"
        "linear-array sound map (sarmap-handheld-sound-map's adapter, on the log's clock) and\n"
        "compares the result with SIM_TRUTH.");
    sarmap::common::NodeArgs node_args;
    std::string log_path, truth_channel = "SIM_TRUTH", robot_config = "config/robot.yaml",
                          live_channel, trajectory;
    bool truth_poses = false, pose_check = false, doa_check = false;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddSwitch(
        "--truth-poses", &truth_poses,
        "diagnosis: the true rig poses (SIM_TRUTH and the camera mount) instead of RIG_POSE");
    parser.AddFlag("--trajectory", &trajectory,
                   "rig poses from this file (utime x y z qw qx qy qz per line: sarmap-log "
                   "rgbd-odometry --output) "
                   "instead of the log's RIG_POSE: try odometry settings offline");
    parser.AddSwitch("--pose-check", &pose_check,
                     "print the rig odometry against the truth every 5 s");
    parser.AddSwitch("--doa-check", &doa_check,
                     "compare every DOA's beta with the true betas of the SIM_TRUTH sources from "
                     "the true rig pose");
    parser.AddFlag("--truth-channel", &truth_channel, "simulator ground truth channel");
    parser.AddFlag(
        "--robot-config", &robot_config,
        "simulated robot (base_from_camera: where the rig, the camera, sits on the robot)");
    parser.AddFlag("--live-channel", &live_channel,
                   "the live node's map to compare too (default: sound_map_channel)");
    const auto parsed =
        sarmap::common::ParseNodeOptions<sarmap::sound_map::HandheldSoundMapOptions>(
            &parser, &node_args, argc, argv, "config/handheld_sound_map.yaml");
    if (!parsed) return 0;
    const auto& options = *parsed;
    if (live_channel.empty()) live_channel = options.sound_map_channel;
    const auto robot = sarmap::common::LoadRobot(robot_config);
    const Eigen::Isometry3d base_from_rig =
        robot.base_from_camera.ToRigid3d().ToIsometry() *
        Eigen::Isometry3d(sarmap::common::BodyFromOpticalRotation().transpose());
    const Eigen::Isometry3d rig_from_sensor =
        sarmap::sound_map::RigFromSensor(options.rig_from_mic_array);

    // Poses of --trajectory (odom_from_rig by utime), fed in time order among the log's inputs.
    std::map<int64_t, Eigen::Isometry3d> file_rig;
    if (!trajectory.empty()) {
      std::ifstream in(trajectory);
      if (!in) throw std::runtime_error("cannot read trajectory " + trajectory);
      for (std::string line; std::getline(in, line);) {
        long long t;
        double x, y, z, qw, qx, qy, qz;
        if (line.empty() || line[0] == '#' ||
            std::sscanf(line.c_str(), "%lld %lf %lf %lf %lf %lf %lf %lf", &t, &x, &y, &z, &qw, &qx,
                        &qy, &qz) != 8)
          continue;
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
        pose.translation() = Eigen::Vector3d(x, y, z);
        file_rig[t] = pose;
      }
      if (file_rig.empty()) throw std::runtime_error("no poses in " + trajectory);
    }

    // sarmap-handheld-sound-map's adapter on the log's clock: its stamp gates, its reorder
    // queue, its map; the rig poses are the log's RIG_POSE, or replaced (--truth-poses,
    // --trajectory) by poses published in their place.
    sarmap::common::Node node("sarmap-log-handheld-sound-map",
                              sarmap::logtools::ReplayNodeArgs(node_args));
    sarmap::sound_map::HandheldSoundMapNode handheld(options, &node);
    sarmap::logtools::NodeReplay replay(&node);
    auto publish_pose = [&](int64_t utime, const Eigen::Isometry3d& odom_from_rig) {
      sarmap::pose_t m{};
      m.header.utime = utime;
      m.header.frame = "odom";
      m.child_frame = "rig";
      const Eigen::Quaterniond q(odom_from_rig.linear());
      sarmap::common::FromRigid3d(sarmap::common::Rigid3d(odom_from_rig.translation(), q),
                                  m.position_m, m.orientation);
      m.node_id = -1;
      std::vector<uint8_t> data(m.getEncodedSize());
      m.encode(data.data(), 0, static_cast<int>(data.size()));
      replay.Inject(options.pose_channel, data);
    };
    std::vector<std::pair<int64_t, std::vector<LinearArraySoundMap::Doa>>> doa_log;
    std::map<int64_t, Eigen::Isometry3d> truth_rig;  // world_from_rig by utime
    std::map<int64_t, Eigen::Isometry3d> odom_rig;   // odom_from_rig by utime, as fed
    sarmap::sim_truth_t truth;
    bool have_truth = false;
    sarmap::sound_map_t live;
    int64_t live_msgs = 0, doa_msgs = 0, ignored_kinds = 0;
    auto next_file_pose = file_rig.begin();
    const auto stats = replay.Run(log_path, [&](sarmap::logtools::LogEvent* e) {
      for (; next_file_pose != file_rig.end() && next_file_pose->first <= e->timestamp_us;
           ++next_file_pose) {
        odom_rig[next_file_pose->first] = next_file_pose->second;
        publish_pose(next_file_pose->first, next_file_pose->second);
      }
      if (e->channel == options.pose_channel) {
        if (truth_poses || !trajectory.empty()) return false;
        sarmap::pose_t msg;
        Eigen::Isometry3d pose;
        if (sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &msg) &&
            sarmap::sound_map::IsometryFromPose(msg, &pose))
          odom_rig[msg.header.utime] = pose;
        return true;
      }
      if (e->channel == options.doa_channel) {
        sarmap::doa_t msg;
        if (sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &msg)) {
          ++doa_msgs;
          const auto doas = sarmap::sound_map::LinearDoasFromMessage(msg, &ignored_kinds);
          if (doa_check && !doas.empty()) doa_log.emplace_back(msg.header.utime, doas);
        }
        return true;
      }
      if (e->channel == options.people_audio_channel) return true;
      if (e->channel == truth_channel) {
        if (!sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &truth)) return false;
        have_truth = true;
        truth_rig[truth.header.utime] =
            sarmap::common::ToRigid3d(truth.robot_position_m, truth.robot_orientation)
                .ToIsometry() *
            base_from_rig;
        if (truth_poses) publish_pose(truth.header.utime, truth_rig[truth.header.utime]);
        return false;
      }
      if (e->channel == live_channel &&
          sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &live))
        ++live_msgs;
      return false;
    });
    for (; next_file_pose != file_rig.end(); ++next_file_pose) {
      odom_rig[next_file_pose->first] = next_file_pose->second;
      publish_pose(next_file_pose->first, next_file_pose->second);
    }
    handheld.Finish();
    replay.Drain();
    for (const auto& p : stats.problems)
      fprintf(stderr, "log damaged at byte %ld: %s\n", static_cast<long>(p.file_offset),
              p.what.c_str());
    if (truth_poses && truth_rig.empty())
      throw std::runtime_error("--truth-poses: no " + truth_channel + " in the log");
    if (!truth_poses && odom_rig.empty())
      throw std::runtime_error("no poses on " + options.pose_channel +
                               " (run sarmap-rgbd-odometry)");
    int64_t refused = 0;
    for (const auto& [channel, st] : node.stats()) refused += st.dropped_malformed;
    printf(
        "log: %zu %s poses, %ld %s messages (%ld DOAs of other kinds ignored), %ld inputs refused "
        "(undecodable, bad pose or stamped far from their stream's clock)%s\n",
        odom_rig.size(), options.pose_channel.c_str(), static_cast<long>(doa_msgs),
        options.doa_channel.c_str(), static_cast<long>(handheld.other_kinds()),
        static_cast<long>(refused + handheld.bad_poses()),
        truth_poses ? "; map from the TRUE rig poses" : "");

    const LinearArraySoundMap& map = handheld.map();
    const auto& c = map.counters();
    printf(
        "map: %ld keyframes, DOAs used %ld of %ld (no pose %ld, gated out %ld, duplicate %ld), "
        "sources born %ld, "
        "converged %ld, merged %ld, pruned %ld, restarted %ld, mirror flips %ld\n",
        static_cast<long>(c.keyframes), static_cast<long>(c.doas_used), static_cast<long>(c.doas),
        static_cast<long>(c.doas_without_pose), static_cast<long>(c.doas_gated_out),
        static_cast<long>(c.doas_duplicate), static_cast<long>(c.sources_born),
        static_cast<long>(c.sources_converged), static_cast<long>(c.sources_merged),
        static_cast<long>(c.sources_pruned), static_cast<long>(c.sources_restarted),
        static_cast<long>(c.mirrors_flipped));

    // world_from_odom: the odometry's frame is the rig at its first pose.
    Eigen::Isometry3d world_from_odom = Eigen::Isometry3d::Identity();
    if (have_truth && !truth_poses) {
      const int64_t t0 = odom_rig.begin()->first;
      auto it = truth_rig.lower_bound(t0);
      if (it == truth_rig.end()) it = std::prev(it);
      world_from_odom = it->second * odom_rig.begin()->second.inverse();
      // The odometry's drift: its poses mapped to the world against the truth at the same time.
      double sum2 = 0, max_err = 0, last_yaw = 0;
      int n = 0;
      int64_t next_print = t0;
      for (const auto& kv : odom_rig) {
        auto tr = truth_rig.lower_bound(kv.first);
        if (tr == truth_rig.end() || tr->first - kv.first > 100000) continue;
        const Eigen::Isometry3d est = world_from_odom * kv.second;
        const double e = (est.translation() - tr->second.translation()).norm();
        if (pose_check && kv.first >= next_print) {
          next_print = kv.first + 5000000;
          const Eigen::Vector3d a = est.translation(), b = tr->second.translation();
          printf(
              "  t %6.1f s  rig (%6.2f %6.2f %5.2f, yaw %6.1f)  truth (%6.2f %6.2f %5.2f, yaw "
              "%6.1f)  error %.2f m\n",
              (kv.first - t0) * 1e-6, a.x(), a.y(), a.z(), Yaw(est) * 180 / M_PI, b.x(), b.y(),
              b.z(), Yaw(tr->second) * 180 / M_PI, e);
        }
        sum2 += e * e;
        max_err = std::max(max_err, e);
        last_yaw = std::remainder(Yaw(est) - Yaw(tr->second), 2 * M_PI);
        ++n;
      }
      if (n)
        printf(
            "rig odometry against the truth: RMS %.3f m, max %.3f m, final heading error %.1f "
            "deg\n",
            std::sqrt(sum2 / n), max_err, last_yaw * 180 / M_PI);
    }
    if (doa_check && have_truth) {
      // Per DOA: the true source whose beta (from the true sensor pose) is nearest.
      std::map<std::string, std::vector<double>> errors;
      for (const auto& [t, doas] : doa_log) {
        auto tr = truth_rig.lower_bound(t);
        if (tr == truth_rig.end()) continue;
        const Eigen::Isometry3d sensor = tr->second * rig_from_sensor;
        for (const auto& d : doas) {
          double best = 1e9;
          std::string name;
          for (const auto& ts : truth.sources) {
            const double b = sarmap::sound_map::LinearArrayBeta(
                sensor, Eigen::Vector3d(ts.position_m[0], ts.position_m[1], ts.position_m[2]));
            if (std::abs(d.beta_rad - b) < std::abs(best)) best = d.beta_rad - b, name = ts.name;
          }
          errors[name].push_back(best * 180 / M_PI);
        }
      }
      printf("\nDOAs against the nearest true beta (from the true rig pose):\n");
      for (auto& [name, e] : errors) {
        std::vector<double> a;
        for (double v : e) a.push_back(std::abs(v));
        std::sort(a.begin(), a.end());
        std::sort(e.begin(), e.end());
        printf(
            "  %-18s %4zu DOAs, |error| median %.1f deg, p90 %.1f deg, signed median %+.1f deg\n",
            name.c_str(), a.size(), a[a.size() / 2], a[a.size() * 9 / 10], e[e.size() / 2]);
      }
    }
    const auto sources = map.sources();
    printf("\nmapped sources (world frame%s):\n", have_truth ? "" : " = odometry frame");
    for (const auto& s : sources) {
      const Eigen::Vector3d p = world_from_odom * s.position_m;
      printf("  %3ld %-12s (%6.2f %6.2f %5.2f) sd_xy %.2f m, %d DOAs, hypotheses %d%s\n",
             static_cast<long>(s.id), s.converged ? "converged" : "initialising", p.x(), p.y(),
             p.z(), std::sqrt(s.covariance.topLeftCorner<2, 2>().trace()), s.observations,
             s.hypotheses_left, s.is_person ? ", person" : "");
    }
    if (!have_truth) return 0;
    printf(
        "\ntrue source            nearest converged (xy / 3D)     nearest any     live node "
        "(converged)\n");
    for (const auto& ts : truth.sources) {
      const Eigen::Vector3d t(ts.position_m[0], ts.position_m[1], ts.position_m[2]);
      double best_xy = 1e9, best_3d = 1e9, best_any = 1e9, best_live = 1e9;
      for (const auto& s : sources) {
        const Eigen::Vector3d p = world_from_odom * s.position_m;
        best_any = std::min(best_any, (p - t).head<2>().norm());
        if (!s.converged) continue;
        if ((p - t).head<2>().norm() < best_xy)
          best_xy = (p - t).head<2>().norm(), best_3d = (p - t).norm();
      }
      for (const auto& s : live.sources) {
        if (s.state != sarmap::sound_source_t::STATE_CONVERGED) continue;
        const Eigen::Vector3d p =
            world_from_odom * Eigen::Vector3d(s.position_m[0], s.position_m[1], s.position_m[2]);
        best_live = std::min(best_live, (p - t).head<2>().norm());
      }
      auto fmt = [](double v) {
        static char buf[4][32];
        static int i = 0;
        i = (i + 1) % 4;
        if (v > 1e8)
          snprintf(buf[i], sizeof buf[i], "none");
        else
          snprintf(buf[i], sizeof buf[i], "%.2f m", v);
        return buf[i];
      };
      printf("  %-18s  %-10s / %-10s          %-10s      %s\n", ts.name.c_str(), fmt(best_xy),
             fmt(best_3d), fmt(best_any), live_msgs ? fmt(best_live) : "(not logged)");
    }
    return 0;
  });
}
