// sarmap-rgbd-odometry: DEPTH (+ RGB for the photometric methods, paired by utime) in,
// RIG_POSE (pose_t, odom_from_rig in the body convention x forward, y left, z up) out. A thin
// adapter around RgbdOdometry (rgbd_odometry.h).

#include <sstream>
#include <vector>

#include "common/logging.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "rgbd_odometry/frame_assembler.h"
#include "rgbd_odometry/rgbd_odometry.h"
#include "rgbd_odometry/rgbd_odometry_node_options.h"
#include "sarmap/image_t.hpp"
#include "sarmap/pose_t.hpp"

using namespace sarmap;
using namespace sarmap::rgbd_odometry;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-rgbd-odometry", [&]() -> int {
    common::ArgParser parser(
        "sarmap-rgbd-odometry",
        "6-DoF odometry of a hand-held RGB-D rig (OpenCV rgbd module): DEPTH (+ RGB for the\n"
        "rgbd and rgbd_icp methods, paired by utime) in, the rig pose out (pose_t on RIG_POSE,\n"
        "frame odom -> rig, body convention x forward, y left, z up; odom = the rig at the\n"
        "first frame).");
    parser.SetEpilog(
        "Examples:\n"
        "  sarmap-depth & sarmap-rgbd-odometry              # OpenNI2 camera -> RIG_POSE\n"
        "  sarmap-rgbd-odometry --set odometry.method=icp   # depth only (dark rooms)\n"
        "  sarmap-rgbd-odometry --set odometry.image_scale=1 --print-config");
    common::NodeArgs node_args;
    const auto parsed = common::ParseNodeOptions<RgbdOdometryNodeOptions>(
        &parser, &node_args, argc, argv, "config/rgbd_odometry.yaml");
    if (!parsed) return 0;
    const RgbdOdometryNodeOptions& options = *parsed;

    RgbdOdometry odometry(options.odometry);
    FrameAssembler assembler(odometry.needs_image(), options.max_pair_dt_s, options.color_wait_s);
    common::Node node("sarmap-rgbd-odometry", node_args);
    auto publisher = node.Advertise<pose_t>(options.pose_channel);
    common::RateLimiter warn_limit(2.0);
    int64_t last_warnings = 0, published = 0, last_utime = 0;
    double total_ms = 0;
    TrackingStatus last_status = TrackingStatus::kInvalidInput;
    std::string last_status_name = "waiting";

    auto update_status = [&]() {
      const RgbdOdometryStats& s = odometry.stats();
      std::ostringstream status;
      status.precision(3);
      status << "state " << last_status_name << " frames " << s.frames << " tracked " << s.tracked
             << " keyframes " << s.keyframes << " lost " << s.lost << " relocalisations "
             << s.relocalisations << " invalid " << s.invalid << " published " << published
             << " input_warnings " << assembler.total_warnings() << " mean_ms "
             << (s.frames > 0 ? total_ms / s.frames : 0.0);
      node.SetStatusMessage(status.str());
    };

    auto process = [&](std::vector<RgbdFrame>& ready) {
      if (assembler.total_warnings() != last_warnings) {
        last_warnings = assembler.total_warnings();
        if (warn_limit.Allow(common::SteadySeconds())) {
          SARMAP_LOG(WARN) << assembler.last_warning() << " (" << last_warnings
                           << " input warnings so far)";
        }
      }
      for (const RgbdFrame& frame : ready) {
        if (last_utime != 0 && frame.utime + 1000000 < last_utime) {
          SARMAP_LOG(WARN) << "time went back from " << last_utime << " to " << frame.utime
                           << " us (a log replayed again?): odometry starts over";
          odometry.Reset();
          total_ms = 0;
        }
        last_utime = frame.utime;
        const RgbdOdometryResult r = odometry.Process(frame);
        total_ms += r.compute_ms;
        if (r.status != last_status) {
          const bool bad =
              r.status == TrackingStatus::kLost || r.status == TrackingStatus::kInvalidInput;
          const std::string line = "frame at " + std::to_string(r.utime) +
                                   " us: " + TrackingStatusName(r.status) +
                                   (r.message.empty() ? "" : ": " + r.message);
          if (!bad) {
            SARMAP_LOG(INFO) << line;
          } else if (warn_limit.Allow(common::SteadySeconds())) {
            SARMAP_LOG(WARN) << line;
          }
          last_status = r.status;
          last_status_name = TrackingStatusName(r.status);
        }
        if (r.status == TrackingStatus::kInvalidInput) continue;
        if (r.status == TrackingStatus::kLost && !options.publish_lost) continue;
        pose_t msg{};
        msg.header.utime = r.utime;
        msg.header.frame = options.frame;
        msg.child_frame = options.child_frame;
        const Eigen::Quaterniond q(r.world_from_rig.linear());
        common::FromRigid3d(common::Rigid3d(r.world_from_rig.translation(), q), msg.position_m,
                            msg.orientation);
        common::FromCovariance6(PoseCovariance(options.covariance, r), msg.covariance);
        msg.node_id = -1;
        publisher.Publish(&msg);
        ++published;
      }
      ready.clear();
      update_status();
    };

    std::vector<RgbdFrame> ready;
    update_status();
    // Odometry wants the newest frames: a short queue lets LCM drop old ones when behind.
    node.Subscribe<image_t>(
        options.depth_channel,
        [&](const image_t& m, const common::ReceiveInfo&) {
          assembler.AddDepth(m, &ready);
          process(ready);
        },
        2);
    if (odometry.needs_image()) {
      node.Subscribe<image_t>(
          options.rgb_channel,
          [&](const image_t& m, const common::ReceiveInfo&) {
            assembler.AddColor(m, &ready);
            process(ready);
          },
          4);
    }
    SARMAP_LOG(INFO) << "listening on " << options.depth_channel
                     << (odometry.needs_image() ? " + " + options.rgb_channel : std::string())
                     << ", publishing " << options.pose_channel << " (method "
                     << options.odometry.method << ", image scale " << options.odometry.image_scale
                     << ")";
    return node.Run();
  });
}
