#include "vision_people/vision_people_node.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "vision_people/detections_message.h"

namespace sarmap {
namespace vision_people {

VisionPeopleNode::VisionPeopleNode(const VisionPeopleOptions& options, common::Node* node)
    : options_(options),
      node_(node),
      detector_(options.detector, InitialGround(options),
                MakeHogClassifier(options.detector.color)),
      tracker_(options.confirmation),
      assembler_(options.max_pair_dt_s, options.color_wait_s, options.require_color),
      decimator_(options.max_rate_hz),
      publisher_(node->Advertise<people_detections_t>(options.output_channel)),
      gates_(options.stamp_gate),
      configured_(MountingFromGround(InitialGround(options))),
      last_message_s_(node->Now()),
      quiet_s_(std::max(1.0, 5 * options.color_wait_s)) {  // a loaded machine may lag 0.2 s
  // Thinned by stamps before decoding: a frame over max_rate_hz costs no decoding.
  assembler_.TakeOnly([this](int64_t utime) { return decimator_.Take(utime); });
  node->AddTimer(0.1, [this] { FlushWhenQuiet(); });
  node->SetStatusMessage(
      "frames 0 bad 0 people 0 colour none input_warnings 0 skipped 0 floor none");
  node->Subscribe<image_t>(
      options_.depth_channel,
      [this](const image_t& m, const common::ReceiveInfo& info) {
        if (!StampOk(kDepthGate, m, info)) return;
        last_message_s_ = info.receive_time_s;
        assembler_.AddDepth(m, &ready_);
        Process();
      },
      4);
  node->Subscribe<image_t>(
      options_.rgb_channel,
      [this](const image_t& m, const common::ReceiveInfo& info) {
        if (!StampOk(kColorGate, m, info)) return;
        last_message_s_ = info.receive_time_s;
        assembler_.AddColor(m, &ready_);
        Process();
      },
      4);
  SARMAP_LOG(INFO) << "listening on " << options_.depth_channel << " + " << options_.rgb_channel
                   << ", publishing " << options_.output_channel << " (hog "
                   << options_.detector.color.hog << ", confirm " << options_.confirmation.k
                   << " of " << options_.confirmation.n << ")";
}

// One frame stamped far ahead would become the assembler's "newest" and every real frame after
// it "not newer".
bool VisionPeopleNode::StampOk(Gate gate, const image_t& m, const common::ReceiveInfo& info) {
  if (gates_.Accept(gate, m.header.utime, info.receive_time_s)) return true;
  node_->Reject(info.channel,
                "stamp " + std::to_string(m.header.utime) + " far from the stream's clock");
  return false;
}

void VisionPeopleNode::FlushWhenQuiet() {
  if (assembler_.has_pending() && node_->Now() - last_message_s_ > quiet_s_) {
    assembler_.Flush(&ready_);
    Process();
  }
}

void VisionPeopleNode::Finish() {
  assembler_.Flush(&ready_);
  Process();
}

void VisionPeopleNode::Process() {
  if (assembler_.total_warnings() != last_warnings_) {
    last_warnings_ = assembler_.total_warnings();
    long suppressed = 0;
    if (warn_limit_.Allow(common::SteadySeconds(), &suppressed)) {
      SARMAP_LOG(WARN) << common::EscapeForLog(assembler_.last_warning(), 512) << " ("
                       << last_warnings_ << " input warnings so far)";
    }
  }
  for (RgbdFrame& frame : ready_) {
    std::string error;
    const DetectionResult result = detector_.Detect(frame, &error);
    Report(frame, result, error);
    const auto confirmed = tracker_.Update(result.people);
    if (observer_) observer_(frame, result, confirmed);
    people_detections_t msg = DetectionsMessage(confirmed, frame.utime, options_.sensor_id);
    published_people_ += msg.num_detections;
    publisher_.Publish(&msg);
  }
  ready_.clear();
  std::ostringstream status;
  status << "frames " << frames_ << " bad " << bad_frames_ << " people " << published_people_
         << " colour " << last_color_state_ << " input_warnings " << assembler_.total_warnings()
         << " skipped " << decimator_.skipped() << " " << floor_status_;
  node_->SetStatusMessage(status.str());
}

void VisionPeopleNode::Report(const RgbdFrame& frame, const DetectionResult& result,
                              const std::string& error) {
  ++frames_;
  if (!error.empty()) {
    ++bad_frames_;
    long suppressed = 0;
    if (warn_limit_.Allow(common::SteadySeconds(), &suppressed)) {
      SARMAP_LOG(WARN) << "frame at " << frame.utime << ": " << common::EscapeForLog(error, 512)
                       << " (" << bad_frames_ << " so far)";
    }
  }
  const std::string state = ColorStateName(result.stats.color_state);
  if (state != last_color_state_) {
    SARMAP_LOG(INFO) << "colour: " << state << " (grey mean " << result.stats.color_mean << ", std "
                     << result.stats.color_std << ")";
    last_color_state_ = state;
  }
  // The floor found in the data against the mounting file: a wrong file is reported, not
  // silently fatal (the detector works from the tracked floor).
  if (result.stats.mounting_mismatch != reported_mismatch_) {
    reported_mismatch_ = result.stats.mounting_mismatch;
    const CameraMounting& m = result.camera;
    if (reported_mismatch_) {
      SARMAP_LOG(WARN) << "the floor seen in the depth puts the camera at height " << m.height_m
                       << " m, tilted down " << m.tilt_down_rad * 180 / M_PI << " deg, roll "
                       << m.roll_rad * 180 / M_PI << " deg; the mounting file says "
                       << configured_.height_m << " m, " << configured_.tilt_down_rad * 180 / M_PI
                       << " deg, " << configured_.roll_rad * 180 / M_PI << " deg ("
                       << options_.robot_config << "): using the floor from the data";
    } else {
      SARMAP_LOG(INFO) << "the floor seen in the depth agrees with the mounting file again";
    }
  }
  std::ostringstream f;
  f.precision(3);
  // seen: this frame's floor; held: this frame's floor jumped away from the track and the
  // track is used; kept: no floor in view, the track (or the mounting file) is used.
  f << "floor "
    << (result.stats.ground_held_off  ? "held"
        : result.stats.ground_refined ? "seen"
                                      : "kept")
    << " height_m " << result.camera.height_m << " tilt_down_deg "
    << result.camera.tilt_down_rad * 180 / M_PI << " roll_deg "
    << result.camera.roll_rad * 180 / M_PI
    << (result.stats.mounting_mismatch ? " MOUNTING_MISMATCH" : "");
  floor_status_ = f.str();
}

}  // namespace vision_people
}  // namespace sarmap
