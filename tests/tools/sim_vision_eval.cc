// bench_sim_vision: the people detector on the simulator's lab, lit and dark (issue 7's
// simulated acceptance). Renders frames along the robot's scripted path, detects people, and
// prints frame recall of the fully visible people (a detection within 0.5 m on the floor) and
// false positives per frame. Prints figures; asserts nothing.
#include <cstdio>
#include <string>

#include "common/robot_config.h"
#include "sim/simulator.h"
#include "sim/renderer.h"
#include "vision_people/people_detector.h"
#include "vision_people/vision_people_options.h"

namespace {

struct NullSink : sarmap::sim::SimSink {
  void Publish(const std::string&, const sarmap::odometry_t&) override {}
  void Publish(const std::string&, const sarmap::image_t&) override {}
  void Publish(const std::string&, const sarmap::audio_frame_t&) override {}
  void Publish(const std::string&, const sarmap::sim_truth_t&) override {}
};

void Evaluate(const std::string& world, double seconds) {
  using namespace sarmap;
  sim::SimOptions options;
  options.world = std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + world + ".yaml";
  options.robot_config = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  options.data_dir = SARMAP_DATA_DIR;
  options.audio.enabled = false;
  sim::Simulator simulator(sim::LoadSetup(options, ""));
  auto vision = common::LoadOptions<vision_people::VisionPeopleOptions>(
      std::string(SARMAP_SOURCE_DIR) + "/config/vision_people.yaml", {});
  vision.robot_config = options.robot_config;
  vision_people::PeopleDetector detector(vision.detector, vision_people::InitialGround(vision),
                                         vision_people::MakeHogClassifier(vision.detector.color));
  const sim::Intrinsics& k = simulator.renderer()->intrinsics();
  NullSink sink;
  int frames = 0, visible = 0, found = 0, false_positives = 0;
  for (double t = 0.0; t <= seconds; t += 0.5) {
    simulator.AdvanceTo(t, &sink);
    const sim::Simulator::View view = simulator.RenderView();
    vision_people::RgbdFrame frame;
    frame.utime = simulator.utime();
    vision_people::PinholeIntrinsics intrinsics;
    intrinsics.fx = k.fx;
    intrinsics.fy = k.fy;
    intrinsics.cx = k.cx;
    intrinsics.cy = k.cy;
    vision_people::CloudFromDepth(view.depth_mm.data(), view.width, view.height, 0.001, intrinsics, &frame);
    frame.rgb = view.rgb;
    const auto result = detector.Detect(frame);
    const common::Rigid3d map_from_camera = simulator.map_from_camera();
    std::vector<Eigen::Vector2d> detections;
    for (const auto& p : result.people) detections.push_back((map_from_camera * p.position_camera).head<2>());
    ++frames;
    const auto& people = simulator.world().people;
    std::vector<bool> used(detections.size(), false);
    for (size_t i = 0; i < people.size() && i < view.person_box.size(); ++i) {
      const auto& box = view.person_box[i];  // x0 y0 x1 y1
      const bool whole = view.person_pixels[i] >= 1500 && box[0] > 2 && box[1] > 2 &&
                         box[2] < view.width - 3 && box[3] < view.height - 3;
      for (size_t d = 0; d < detections.size(); ++d) {
        if ((detections[d] - people[i].position).norm() <= 0.5) used[d] = true;
      }
      if (!whole) continue;
      ++visible;
      for (const auto& d : detections) {
        if ((d - people[i].position).norm() <= 0.5) {
          ++found;
          break;
        }
      }
    }
    for (bool u : used) false_positives += u ? 0 : 1;
  }
  printf("%-10s frames %3d  fully visible person-frames %3d  found %3d  frame recall %.3f  false positives/frame %.3f\n",
         world.c_str(), frames, visible, found, visible ? static_cast<double>(found) / visible : 0.0,
         static_cast<double>(false_positives) / frames);
}

}  // namespace

int main() {
  Evaluate("lab_lit", 40.0);
  Evaluate("lab_dark", 40.0);
  return 0;
}
