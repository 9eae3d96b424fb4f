// bench_sim_vision: the people detector on the simulator's lab, lit and dark (issue 7's
// simulated acceptance). Renders frames along the robot's scripted path, detects people, and
// prints frame recall of the fully visible people (a detection within 0.5 m on the floor) and
// false positives per frame. Prints figures; asserts nothing.
#include <cstdio>
#include <string>
#include <vector>

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

bool g_verbose = false;
std::vector<std::string> g_overrides;  // --set key=value (options of config/vision_people.yaml)

void Evaluate(const std::string& world, double seconds) {
  using namespace sarmap;
  sim::SimOptions options;
  options.world = std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + world + ".yaml";
  options.robot_config = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  options.data_dir = SARMAP_DATA_DIR;
  options.audio.enabled = false;
  sim::Simulator simulator(sim::LoadSetup(options, ""));
  auto vision = common::LoadOptions<vision_people::VisionPeopleOptions>(
      std::string(SARMAP_SOURCE_DIR) + "/config/vision_people.yaml", g_overrides);
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
    if (g_verbose) {
      printf("t %5.1f ground n %.3f %.3f %.3f d %.3f refined %d used %d candidates %d people %d\n", t,
             result.ground.normal.x(), result.ground.normal.y(), result.ground.normal.z(),
             result.ground.offset, result.stats.ground_refined, result.stats.num_ground_voxels,
             result.stats.num_candidates, static_cast<int>(result.people.size()));
    }
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
      bool hit = false;
      for (const auto& d : detections) {
        if ((d - people[i].position).norm() <= 0.5) {
          hit = true;
          break;
        }
      }
      found += hit;
      if (g_verbose) {
        // Nearest candidate (accepted or rejected) to this person: where was it lost?
        const vision_people::PersonCandidate* best = nullptr;
        double best_d = 1e9;
        for (const auto* list : {&result.people, &result.rejected}) {
          for (const auto& c : *list) {
            const double dd = ((map_from_camera * c.position_camera).head<2>() - people[i].position).norm();
            if (dd < best_d) { best_d = dd; best = &c; }
          }
        }
        const double range = (people[i].position - map_from_camera.translation().head<2>()).norm();
        printf("  t %5.1f person %zu range %.2f px %5d box %3d %3d %3d %3d %s", t, i, range,
               view.person_pixels[i], box[0], box[1], box[2], box[3], hit ? "FOUND" : "lost ");
        if (best) {
          printf(" cand d %.2f H %.2f bot %.2f w %.2f dep %.2f headw %.2f prom %.2f ratio %.2f fill %.2f vis %.2f trunc %d depth %.2f hog %d %.2f conf %.2f acc %d\n",
                 best_d, best->height_m, best->bottom_m, best->width_m, best->depth_extent_m,
                 best->head_width_m, best->head_prominence_m,
                 best->shoulder_area_m2 > 0 ? best->head_area_m2 / best->shoulder_area_m2 : 1.0,
                 best->fill, best->visible_fraction, best->truncated_top, best->depth_score,
                 best->hog_used, best->hog_score, best->confidence, best->accepted);
        } else {
          printf(" no candidate (clusters %d, ground refined %d)\n", result.stats.num_clusters,
                 result.stats.ground_refined);
        }
      }
    }
    for (bool u : used) false_positives += u ? 0 : 1;
    if (g_verbose) {
      // Candidates that are nobody (accepted: false positives; rejected: correctly refused).
      for (const auto* list : {&result.people, &result.rejected}) {
        for (const auto& c : *list) {
          const Eigen::Vector2d xy = (map_from_camera * c.position_camera).head<2>();
          bool person = false;
          for (const auto& p : people) person = person || (xy - p.position).norm() <= 0.5;
          if (person) continue;
          printf("  t %5.1f other at %.2f %.2f %s H %.2f bot %.2f w %.2f dep %.2f headw %.2f prom %.2f fill %.2f vis %.2f trunc %d depth %.2f hog %d %.2f conf %.2f\n",
                 t, xy.x(), xy.y(), c.accepted ? "FALSE-POSITIVE" : "rejected", c.height_m, c.bottom_m,
                 c.width_m, c.depth_extent_m, c.head_width_m, c.head_prominence_m, c.fill,
                 c.visible_fraction, c.truncated_top, c.depth_score, c.hog_used, c.hog_score,
                 c.confidence);
        }
      }
    }
  }
  printf("%-10s frames %3d  fully visible person-frames %3d  found %3d  frame recall %.3f  false positives/frame %.3f\n",
         world.c_str(), frames, visible, found, visible ? static_cast<double>(found) / visible : 0.0,
         static_cast<double>(false_positives) / frames);
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--verbose") {
      g_verbose = true;
    } else if (arg == "--set" && i + 1 < argc) {
      g_overrides.push_back(argv[++i]);
    } else {
      fprintf(stderr, "usage: bench_sim_vision [--verbose] [--set key=value]...\n");
      return 2;
    }
  }
  Evaluate("lab_lit", 40.0);
  Evaluate("lab_dark", 40.0);
  return 0;
}
