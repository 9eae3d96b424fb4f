#pragma once
// VisionPeopleNode: the LCM adapter of the people detector. DEPTH + RGB (image_t, paired by
// utime) in, PEOPLE_VISUAL (people_detections_t, camera optical frame) out: ground-based RGB-D
// people detection with a depth-only fallback in darkness and glare, confirmed over k of n
// frames. Each image stream is gated on its own clock (common/stamp_gate.h).

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/logging.h"
#include "common/node.h"
#include "common/stamp_decimator.h"
#include "common/stamp_gate.h"
#include "vision_people/confirmation_tracker.h"
#include "vision_people/frame_assembler.h"
#include "vision_people/people_detector.h"
#include "vision_people/vision_people_options.h"

namespace sarmap {
namespace vision_people {

class VisionPeopleNode {
 public:
  VisionPeopleNode(const VisionPeopleOptions& options, common::Node* node);

  // At the end (SIGINT/SIGTERM, or the end of a replayed log): the frame still waiting for its
  // pair is processed and published.
  void Finish();

  // For replay tools: called for every frame processed, with the detector's result and the
  // people the k-of-n confirmation accepted (what PEOPLE_VISUAL then carries).
  using FrameObserver = std::function<void(const RgbdFrame&, const DetectionResult&,
                                           const std::vector<ConfirmedPerson>&)>;
  void set_frame_observer(FrameObserver observer) { observer_ = std::move(observer); }

  int64_t frames() const { return frames_; }
  // Frames left out to keep to max_rate_hz.
  int64_t skipped_frames() const { return decimator_.skipped(); }
  int64_t bad_frames() const { return bad_frames_; }
  // Frame-pairing warnings by kind (FrameAssembler::warnings).
  const std::map<std::string, int64_t>& pairing_warnings() const { return assembler_.warnings(); }

 private:
  enum Gate { kDepthGate = 0, kColorGate = 1 };

  bool StampOk(Gate gate, const image_t& m, const common::ReceiveInfo& info);
  // Detects in every assembled frame, publishes each frame's confirmed people.
  void Process();
  void Report(const RgbdFrame& frame, const DetectionResult& result, const std::string& error);
  // When the bus goes quiet, a depth frame still waiting for its colour is processed
  // depth-only (the last frame of a depth-only replay would wait for ever).
  void FlushWhenQuiet();

  VisionPeopleOptions options_;
  common::Node* node_;
  PeopleDetector detector_;
  ConfirmationTracker tracker_;
  FrameAssembler assembler_;
  common::StampDecimator decimator_;
  common::Node::Publisher<people_detections_t> publisher_;
  common::StampGates gates_;
  common::RateLimiter warn_limit_{2.0};
  CameraMounting configured_;
  std::vector<RgbdFrame> ready_;
  double last_message_s_;
  double quiet_s_;
  int64_t frames_ = 0, bad_frames_ = 0, published_people_ = 0, last_warnings_ = 0;
  std::string last_color_state_;
  bool reported_mismatch_ = false;
  std::string floor_status_ = "floor none";
  FrameObserver observer_;
};

}  // namespace vision_people
}  // namespace sarmap
