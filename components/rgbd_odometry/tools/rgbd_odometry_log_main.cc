// sarmap-log-rgbd-odometry: runs sarmap-rgbd-odometry's adapter (RgbdOdometryNode: frame
// pairing, RgbdOdometry, restart when time goes back) over a log's DEPTH and RGB on the log's
// clock (logtools::NodeReplay), as fast as the CPU allows, prints its
// tracking statistics and, when the log holds SIM_TRUTH, its drift against the simulated
// camera; --output writes the trajectory for sarmap-log handheld-sound-map --trajectory.
//
//   sarmap-log rgbd-odometry run.lcmlog [--set odometry.method=icp] [--output rig.txt]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <stdexcept>

#include "common/args.h"
#include "common/decode.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "log-tools/node_replay.h"
#include "rgbd_odometry/rgbd_odometry_node.h"
#include "sarmap/sim_truth_t.hpp"

namespace {

using sarmap::rgbd_odometry::RgbdOdometryResult;

double Yaw(const Eigen::Isometry3d& m) {
  const Eigen::Vector3d x = m.linear().col(0);
  return std::atan2(x.y(), x.x());
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-log-rgbd-odometry", [&] {
    sarmap::common::ArgParser parser(
        "sarmap-log-rgbd-odometry",
        "Runs the hand-held rig's RGB-D odometry over a log's DEPTH (and RGB) frames, as\n"
        "sarmap-rgbd-odometry would, and compares it with SIM_TRUTH when the log has it.");
    sarmap::common::NodeArgs node_args;
    std::string log_path, output, truth_channel = "SIM_TRUTH", robot_config = "config/robot.yaml";
    double check_every_s = 0;
    parser.AddPositional("log", &log_path, "LCM log file");
    parser.AddFlag("--output", &output,
                   "write the rig trajectory here: utime x y z qw qx qy qz per tracked frame");
    parser.AddFlag("--truth-channel", &truth_channel, "simulator ground truth channel");
    parser.AddFlag("--robot-config", &robot_config,
                   "simulated robot (base_from_camera: where the camera sits)");
    parser.AddFlag("--check-every", &check_every_s,
                   "print the pose against the truth every this many seconds (0: off)");
    bool print_large_steps = false;
    parser.AddSwitch("--print-large-steps", &print_large_steps,
                     "print every frame-to-frame step over 3 cm with its overlap and status");
    const auto parsed =
        sarmap::common::ParseNodeOptions<sarmap::rgbd_odometry::RgbdOdometryNodeOptions>(
            &parser, &node_args, argc, argv, "config/rgbd_odometry.yaml");
    if (!parsed) return 0;
    const auto& options = *parsed;
    const auto robot = sarmap::common::LoadRobot(robot_config);
    const Eigen::Isometry3d base_from_optical = robot.base_from_camera.ToRigid3d().ToIsometry();
    const Eigen::Isometry3d base_from_rig =
        base_from_optical * sarmap::rgbd_odometry::RigFromOptical().inverse();

    std::ofstream out;
    if (!output.empty()) {
      out.open(output);
      if (!out) throw std::runtime_error("cannot write " + output);
      out << "# utime x y z qw qx qy qz (odom_from_rig, sarmap-log rgbd-odometry " << log_path
          << ")\n";
    }
    std::map<int64_t, Eigen::Isometry3d> truth_rig;
    std::vector<RgbdOdometryResult> results;
    std::map<std::string, int64_t> statuses;
    double compute_ms = 0;
    // sarmap-rgbd-odometry's adapter on the log's clock: its frame pairing, its restart when
    // time goes back, every frame's result observed.
    sarmap::common::Node node("sarmap-log-rgbd-odometry",
                              sarmap::logtools::ReplayNodeArgs(node_args));
    sarmap::rgbd_odometry::RgbdOdometryNode odometry_node(options, &node);
    odometry_node.set_result_observer([&](const RgbdOdometryResult& r) {
      if (print_large_steps && r.previous_from_rig.translation().norm() > 0.03)
        fprintf(stderr, "frame %ld: step %.3f m %.1f deg overlap %.2f valid %.2f keyframe %d %s\n",
                static_cast<long>(r.utime), r.previous_from_rig.translation().norm(),
                Eigen::AngleAxisd(r.previous_from_rig.linear()).angle() * 180 / M_PI,
                r.overlap_fraction, r.valid_depth_fraction, r.keyframe, r.message.c_str());
      ++statuses[sarmap::rgbd_odometry::TrackingStatusName(r.status)];
      compute_ms += r.compute_ms;
      if (!r.ok()) return;
      results.push_back(r);
      if (out) {
        const Eigen::Quaterniond q(r.world_from_rig.linear());
        const Eigen::Vector3d t = r.world_from_rig.translation();
        out << r.utime << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.w() << ' '
            << q.x() << ' ' << q.y() << ' ' << q.z() << '\n';
      }
    });
    sarmap::logtools::NodeReplay replay(&node);
    int64_t frames = 0;
    const auto stats = replay.Run(log_path, [&](sarmap::logtools::LogEvent* e) {
      if (e->channel == options.depth_channel) {
        ++frames;
        return true;
      }
      if (e->channel == options.rgb_channel) return true;
      if (e->channel != truth_channel) return false;
      sarmap::sim_truth_t m;
      if (!sarmap::common::DecodeMessage(e->data.data(), e->data.size(), &m)) return false;
      truth_rig[m.header.utime] =
          sarmap::common::ToRigid3d(m.robot_position_m, m.robot_orientation).ToIsometry() *
          base_from_rig;
      return false;
    });
    replay.Drain();
    for (const auto& p : stats.problems)
      fprintf(stderr, "log damaged at byte %ld: %s\n", static_cast<long>(p.file_offset),
              p.what.c_str());
    const auto& st = odometry_node.odometry().stats();
    printf("%ld depth frames, %ld processed: ", static_cast<long>(frames),
           static_cast<long>(st.frames));
    for (const auto& [name, n] : statuses) printf("%s %ld  ", name.c_str(), static_cast<long>(n));
    printf("\n%s, image scale %.2f: %.1f ms per frame (this machine, one thread)\n",
           options.odometry.method.c_str(), options.odometry.image_scale,
           st.frames ? compute_ms / static_cast<double>(st.frames) : 0.0);
    for (const auto& [name, n] : odometry_node.pairing_warnings())
      printf("  pairing: %s %ld\n", name.c_str(), static_cast<long>(n));
    if (truth_rig.empty() || results.empty()) return 0;
    // The odometry's world is the rig at its first frame.
    auto truth_at = [&](int64_t t) {
      auto it = truth_rig.lower_bound(t);
      if (it == truth_rig.end()) --it;
      return it->second;
    };
    const Eigen::Isometry3d world_from_odom =
        truth_at(results.front().utime) * results.front().world_from_rig.inverse();
    double sum2 = 0, max_err = 0, path = 0, yaw_err = 0;
    Eigen::Vector3d prev = truth_at(results.front().utime).translation();
    int64_t next_check = results.front().utime;
    for (const auto& r : results) {
      const Eigen::Isometry3d est = world_from_odom * r.world_from_rig, tr = truth_at(r.utime);
      const double e = (est.translation() - tr.translation()).norm();
      sum2 += e * e;
      max_err = std::max(max_err, e);
      path += (tr.translation() - prev).norm();
      prev = tr.translation();
      yaw_err = std::remainder(Yaw(est) - Yaw(tr), 2 * M_PI);
      if (check_every_s > 0 && r.utime >= next_check) {
        next_check = r.utime + static_cast<int64_t>(check_every_s * 1e6);
        printf("  t %6.1f s  error (%+.2f %+.2f %+.2f) m, yaw %+.1f deg  [%s]\n",
               (r.utime - results.front().utime) * 1e-6,
               est.translation().x() - tr.translation().x(),
               est.translation().y() - tr.translation().y(),
               est.translation().z() - tr.translation().z(), yaw_err * 180 / M_PI,
               sarmap::rgbd_odometry::TrackingStatusName(r.status));
      }
    }
    printf(
        "against SIM_TRUTH over %.1f m of path: RMS %.3f m, max %.3f m, final %.3f m (%.1f %% of "
        "the path), "
        "final yaw error %+.1f deg\n",
        path, std::sqrt(sum2 / results.size()), max_err,
        ((world_from_odom * results.back().world_from_rig).translation() -
         truth_at(results.back().utime).translation())
            .norm(),
        path > 0 ? 100 *
                       ((world_from_odom * results.back().world_from_rig).translation() -
                        truth_at(results.back().utime).translation())
                           .norm() /
                       path
                 : 0.0,
        yaw_err * 180 / M_PI);
    return 0;
  });
}
