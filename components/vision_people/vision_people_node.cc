// sarmap-vision-people: DEPTH + RGB (image_t, paired by utime) in, PEOPLE_VISUAL
// (people_detections_t, camera frame) out. Ground-based RGB-D people detection with a
// depth-only fallback in darkness and glare, confirmed over k of n frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/logging.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/options.h"
#include "sarmap/people_detections_t.hpp"
#include "vision_people/confirmation_tracker.h"
#include "vision_people/detections_message.h"
#include "vision_people/frame_assembler.h"
#include "vision_people/vision_people_options.h"

using namespace sarmap;
using namespace sarmap::vision_people;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-vision-people", [&] {
    common::ArgParser parser(
        "sarmap-vision-people",
        "Detects people in RGB-D frames (DEPTH + RGB image_t, paired by utime) and publishes\n"
        "them on PEOPLE_VISUAL (people_detections_t, camera optical frame). Ground-based\n"
        "clustering with HOG on the colour patch; a depth-only shape classifier takes over in\n"
        "darkness and glare. People are reported after k of n frames.");
    common::NodeArgs node_args;
    const auto parsed = common::ParseNodeOptions<VisionPeopleOptions>(
        &parser, &node_args, argc, argv, "config/vision_people.yaml");
    if (!parsed) return 0;
    const VisionPeopleOptions& options = *parsed;
    PeopleDetector detector(options.detector, InitialGround(options),
                            MakeHogClassifier(options.detector.color));
    ConfirmationTracker tracker(options.confirmation);
    FrameAssembler assembler(options.max_pair_dt_s, options.color_wait_s, options.require_color);
    common::Node node("sarmap-vision-people", node_args);
    auto publisher = node.Advertise<people_detections_t>(options.output_channel);
    common::RateLimiter warn_limit(2.0);
    int64_t frames = 0, bad_frames = 0, published_people = 0, last_warnings = 0;
    std::string last_color_state;
    bool reported_mismatch = false;
    std::string floor_status = "floor none";
    const CameraMounting configured = MountingFromGround(InitialGround(options));

    auto process = [&](std::vector<RgbdFrame>& ready) {
      if (assembler.total_warnings() != last_warnings) {
        last_warnings = assembler.total_warnings();
        long suppressed = 0;
        if (warn_limit.Allow(common::SteadySeconds(), &suppressed)) {
          SARMAP_LOG(WARN) << common::EscapeForLog(assembler.last_warning(), 512) << " ("
                           << last_warnings << " input warnings so far)";
        }
      }
      for (RgbdFrame& frame : ready) {
        std::string error;
        const DetectionResult result = detector.Detect(frame, &error);
        ++frames;
        if (!error.empty()) {
          ++bad_frames;
          long suppressed = 0;
          if (warn_limit.Allow(common::SteadySeconds(), &suppressed)) {
            SARMAP_LOG(WARN) << "frame at " << frame.utime << ": "
                             << common::EscapeForLog(error, 512) << " (" << bad_frames
                             << " so far)";
          }
        }
        const std::string state = ColorStateName(result.stats.color_state);
        if (state != last_color_state) {
          SARMAP_LOG(INFO) << "colour: " << state << " (grey mean " << result.stats.color_mean
                           << ", std " << result.stats.color_std << ")";
          last_color_state = state;
        }
        // The floor found in the data against the mounting file: a wrong file is reported, not
        // silently fatal (the detector works from the tracked floor).
        if (result.stats.mounting_mismatch != reported_mismatch) {
          reported_mismatch = result.stats.mounting_mismatch;
          const CameraMounting& m = result.camera;
          if (reported_mismatch) {
            SARMAP_LOG(WARN) << "the floor seen in the depth puts the camera at height "
                             << m.height_m << " m, tilted down " << m.tilt_down_rad * 180 / M_PI
                             << " deg, roll " << m.roll_rad * 180 / M_PI
                             << " deg; the mounting file says " << configured.height_m << " m, "
                             << configured.tilt_down_rad * 180 / M_PI << " deg, "
                             << configured.roll_rad * 180 / M_PI << " deg (" << options.robot_config
                             << "): using the floor from the data";
          } else {
            SARMAP_LOG(INFO) << "the floor seen in the depth agrees with the mounting file again";
          }
        }
        {
          std::ostringstream f;
          f.precision(3);
          f << "floor " << (result.stats.ground_refined ? "seen" : "kept") << " height_m "
            << result.camera.height_m << " tilt_down_deg "
            << result.camera.tilt_down_rad * 180 / M_PI << " roll_deg "
            << result.camera.roll_rad * 180 / M_PI
            << (result.stats.mounting_mismatch ? " MOUNTING_MISMATCH" : "");
          floor_status = f.str();
        }
        const auto confirmed = tracker.Update(result.people);
        people_detections_t msg = DetectionsMessage(confirmed, frame.utime, options.sensor_id);
        published_people += msg.num_detections;
        publisher.Publish(&msg);
      }
      ready.clear();
      std::ostringstream status;
      status << "frames " << frames << " bad " << bad_frames << " people " << published_people
             << " colour " << last_color_state << " input_warnings " << assembler.total_warnings()
             << " " << floor_status;
      node.SetStatusMessage(status.str());
    };

    std::vector<RgbdFrame> ready;
    // When the bus goes quiet, a depth frame still waiting for its colour is processed
    // depth-only (the last frame of a depth-only replay would wait for ever).
    double last_message_s = common::SteadySeconds();
    const double quiet_s =
        std::max(1.0, 5 * options.color_wait_s);  // a loaded machine may lag 0.2 s
    node.AddTimer(0.1, [&] {
      if (assembler.has_pending() && common::SteadySeconds() - last_message_s > quiet_s) {
        assembler.Flush(&ready);
        process(ready);
      }
    });
    node.SetStatusMessage("frames 0 bad 0 people 0 colour none input_warnings 0 floor none");
    // One frame stamped far ahead would become the assembler's "newest" and every real frame
    // after it "not newer": each stream is gated on its own clock (common/stamp_gate.h).
    constexpr int kDepthGate = 0, kColorGate = 1;
    common::StampGates gates(options.stamp_gate);
    const auto stamp_ok = [&](int gate, const image_t& m, const common::ReceiveInfo& info) {
      if (gates.Accept(gate, m.header.utime, info.receive_time_s)) return true;
      node.Reject(info.channel,
                  "stamp " + std::to_string(m.header.utime) + " far from the stream's clock");
      return false;
    };
    node.Subscribe<image_t>(
        options.depth_channel,
        [&](const image_t& m, const common::ReceiveInfo& info) {
          if (!stamp_ok(kDepthGate, m, info)) return;
          last_message_s = common::SteadySeconds();
          assembler.AddDepth(m, &ready);
          process(ready);
        },
        4);
    node.Subscribe<image_t>(
        options.rgb_channel,
        [&](const image_t& m, const common::ReceiveInfo& info) {
          if (!stamp_ok(kColorGate, m, info)) return;
          last_message_s = common::SteadySeconds();
          assembler.AddColor(m, &ready);
          process(ready);
        },
        4);
    SARMAP_LOG(INFO) << "listening on " << options.depth_channel << " + " << options.rgb_channel
                     << ", publishing " << options.output_channel << " (hog "
                     << options.detector.color.hog << ", confirm " << options.confirmation.k
                     << " of " << options.confirmation.n << ")";
    return node.Run();
  });
}
