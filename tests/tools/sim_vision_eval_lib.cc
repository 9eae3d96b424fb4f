#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/robot_config.h"
#include "sim/renderer.h"
#include "sim/simulator.h"
#include "tools/sim_vision_eval.h"
#include "vision_people/confirmation_tracker.h"
#include "vision_people/people_detector.h"
#include "vision_people/vision_people_options.h"

namespace sarmap {
namespace sim_vision {
namespace {

struct NullSink : sim::SimSink {
  void Publish(const std::string&, const odometry_t&) override {}
  void Publish(const std::string&, const image_t&) override {}
  void Publish(const std::string&, const audio_frame_t&) override {}
  void Publish(const std::string&, const sim_truth_t&) override {}
  void Publish(const std::string&, const occupancy_grid_t&) override {}
};

double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// Counts found people (fully visible ones only) and false positives among `detections`
// (map-frame floor positions).
void Score(const std::vector<Eigen::Vector2d>& detections, const std::vector<sim::Person>& people,
           const std::vector<bool>& whole, int* found, int* false_positives,
           std::vector<bool>* hit) {
  std::vector<bool> used(detections.size(), false);
  hit->assign(people.size(), false);
  for (size_t i = 0; i < people.size(); ++i) {
    for (size_t d = 0; d < detections.size(); ++d) {
      if ((detections[d] - people[i].position).norm() <= 0.5) {
        used[d] = true;
        (*hit)[i] = true;
      }
    }
    if (whole[i] && (*hit)[i]) ++*found;
  }
  for (bool u : used) *false_positives += u ? 0 : 1;
}

void PrintCandidate(const vision_people::PersonCandidate& c) {
  printf(
      "%su %.0f v %.0f..%.0f H %.2f bot %.2f len %.2f relief %.2f w %.2f dep %.2f headw %.2f prom "
      "%.2f ratio %.2f fill %.2f vis %.2f trunc %d "
      "depth %.2f hog %d %.2f conf %.2f acc %d\n",
      c.lying ? "LYING " : "", c.box_u_center, c.box_v_top, c.box_v_bottom, c.height_m, c.bottom_m,
      c.length_m, c.relief_m, c.width_m, c.depth_extent_m, c.head_width_m, c.head_prominence_m,
      c.shoulder_area_m2 > 0 ? c.head_area_m2 / c.shoulder_area_m2 : 1.0, c.fill,
      c.visible_fraction, c.truncated_top, c.depth_score, c.hog_used, c.hog_score, c.confidence,
      c.accepted);
}

// A copy of the robot file with the camera at another height and tilt (base_from_camera's
// z_m and roll_rad = -pi/2 - tilt down), in /tmp.
std::string MountedRobotFile(const std::string& robot_file, const EvalOptions& eval) {
  std::ifstream in(robot_file);
  if (!in) throw std::runtime_error("cannot read " + robot_file);
  std::ostringstream out;
  std::string line;
  bool in_camera = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != ' ') in_camera = line.rfind("base_from_camera:", 0) == 0;
    if (in_camera && line.find("z_m:") != std::string::npos) {
      line = "  z_m: " + std::to_string(eval.camera_height_m);
    } else if (in_camera && line.find("roll_rad:") != std::string::npos) {
      line = "  roll_rad: " + std::to_string(-M_PI / 2 - eval.camera_tilt_down_deg * M_PI / 180);
    }
    out << line << "\n";
  }
  const std::string path = "/tmp/sarmap_sim_vision_robot_" + std::to_string(getpid()) + ".yaml";
  std::ofstream(path) << out.str();
  return path;
}

}  // namespace

Figures Evaluate(const EvalOptions& eval) {
  sim::SimOptions options;
  options.world = std::string(SARMAP_SOURCE_DIR) + "/config/worlds/" + eval.world + ".yaml";
  const std::string robot_file = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  options.robot_config = robot_file;
  if (eval.camera_height_m >= 0) {
    options.robot_config = MountedRobotFile(robot_file, eval);
    // The copy lives in /tmp: name the array file beside the original.
    options.audio.mic_array = std::string(SARMAP_SOURCE_DIR) + "/config/arrays/" +
                              common::LoadRobot(robot_file).mic_array + ".yaml";
  }
  options.data_dir = SARMAP_DATA_DIR;
  options.audio.enabled = false;
  options.seed = eval.seed;
  // Frames are rendered here (RenderView); the simulator's own 30 Hz DEPTH/RGB stream would
  // only be thrown away (and costs most of the run time).
  options.camera.rate_hz = 0.01;
  sim::Simulator simulator(sim::LoadSetup(options, ""));
  if (options.robot_config != robot_file)
    std::remove(options.robot_config.c_str());  // read: no longer needed
  auto vision = common::LoadOptions<vision_people::VisionPeopleOptions>(
      std::string(SARMAP_SOURCE_DIR) + "/config/vision_people.yaml", eval.overrides);
  vision.robot_config = robot_file;
  vision_people::PeopleDetector detector(vision.detector, vision_people::InitialGround(vision),
                                         vision_people::MakeHogClassifier(vision.detector.color));
  vision_people::ConfirmationTracker confirmation(vision.confirmation);
  const sim::Intrinsics& k = simulator.renderer()->intrinsics();
  vision_people::PinholeIntrinsics intrinsics;
  intrinsics.fx = k.fx;
  intrinsics.fy = k.fy;
  intrinsics.cx = k.cx;
  intrinsics.cy = k.cy;
  NullSink sink;
  Figures fig;
  fig.confirm_k = vision.confirmation.k;
  fig.confirm_n = vision.confirmation.n;
  double cpu_sum = 0;
  const auto& people = simulator.world().people;
  // The depth's field of view is narrower than the colour image (registered depth): a person
  // counts as whole when its box lies inside the depth's field, 2 px in from its border.
  const int depth_u0 =
      2 + static_cast<int>(options.camera.width / 2.0 *
                           (1.0 - std::tan(options.camera.depth_hfov_deg * M_PI / 360) /
                                      std::tan(options.camera.color_hfov_deg * M_PI / 360)));
  const int depth_v0 =
      2 + static_cast<int>(options.camera.height / 2.0 *
                           (1.0 - std::tan(options.camera.depth_vfov_deg * M_PI / 360) /
                                      std::tan(options.camera.color_vfov_deg * M_PI / 360)));
  const int steps = static_cast<int>(eval.seconds / eval.step_s + 1e-9);
  for (int step = 0; step <= steps; ++step) {
    const double t = step * eval.step_s;
    simulator.AdvanceTo(t, &sink);
    if (eval.spin_deg_per_step > 0) {
      const Eigen::Vector3d& start = simulator.world().robot.pose;
      simulator.SetRobotPose(common::Rigid2d(
          start.x(), start.y(), start.z() + step * eval.spin_deg_per_step * M_PI / 180));
    }
    const sim::Simulator::View view = simulator.RenderView();
    vision_people::RgbdFrame frame;
    frame.utime = simulator.utime();
    vision_people::CloudFromDepth(view.depth_mm.data(), view.width, view.height, 0.001, intrinsics,
                                  &frame);
    frame.rgb = view.rgb;
    const double c0 = ThreadCpuSeconds();
    const vision_people::DetectionResult result = detector.Detect(frame);
    const double cpu_ms = 1e3 * (ThreadCpuSeconds() - c0);
    cpu_sum += cpu_ms;
    fig.detect_cpu_ms_max = std::max(fig.detect_cpu_ms_max, cpu_ms);
    ++fig.frames;

    const common::Rigid3d map_from_camera = simulator.map_from_camera();
    auto on_floor = [&](const Eigen::Vector3d& p) {
      return (map_from_camera * p).head<2>().eval();
    };
    std::vector<bool> whole(people.size(), false);
    for (size_t i = 0; i < people.size() && i < view.person_box.size(); ++i) {
      const auto& box = view.person_box[i];  // x0 y0 x1 y1
      // The simulator counts body pixels before its depth range cut: a person beyond the
      // Kinect's range (corridor_glass) is in view but has no depth at all.
      const double range = (people[i].position - map_from_camera.translation().head<2>()).norm();
      whole[i] = view.person_pixels[i] >= 1500 && box[0] > depth_u0 && box[1] > depth_v0 &&
                 box[2] < view.width - 1 - depth_u0 && box[3] < view.height - 1 - depth_v0 &&
                 range <= options.camera.max_range_m;
      fig.visible += whole[i];
      fig.by_posture[static_cast<int>(people[i].posture) - 1].visible += whole[i];
    }
    std::vector<Eigen::Vector2d> detections, confirmed;
    for (const auto& p : result.people) detections.push_back(on_floor(p.position_camera));
    for (const auto& p : confirmation.Update(result.people))
      confirmed.push_back(on_floor(p.person.position_camera));
    std::vector<bool> hit, confirmed_hit;
    Score(detections, people, whole, &fig.found, &fig.false_positives, &hit);
    for (size_t i = 0; i < people.size(); ++i) {
      fig.by_posture[static_cast<int>(people[i].posture) - 1].found += whole[i] && hit[i];
    }
    Score(confirmed, people, whole, &fig.confirmed_found, &fig.confirmed_false_positives,
          &confirmed_hit);
    const Eigen::Vector2d camera_xy = map_from_camera.translation().head<2>();
    for (size_t i = 0; i < people.size(); ++i) {
      if (!whole[i] || !hit[i]) continue;
      const Eigen::Vector2d* nearest = nullptr;
      for (const auto& d : detections) {
        if (!nearest || (d - people[i].position).norm() < (*nearest - people[i].position).norm())
          nearest = &d;
      }
      const Eigen::Vector2d ray = (people[i].position - camera_xy).normalized();
      const Eigen::Vector2d error = *nearest - people[i].position;
      const double along = error.dot(ray), across = error.x() * ray.y() - error.y() * ray.x();
      ++fig.placed;
      fig.range_error_sum_m += along;
      fig.range_error_sq_sum_m2 += along * along;
      fig.cross_error_sq_sum_m2 += across * across;
    }

    if (!eval.verbose) continue;
    printf(
        "t %5.1f ground n %.3f %.3f %.3f d %.3f refined %d floor voxels %d candidates %d accepted "
        "%d "
        "confirmed %zu cpu %.1f ms\n",
        t, result.ground.normal.x(), result.ground.normal.y(), result.ground.normal.z(),
        result.ground.offset, result.stats.ground_refined, result.stats.num_ground_voxels,
        result.stats.num_candidates, static_cast<int>(result.people.size()), confirmed.size(),
        cpu_ms);
    for (size_t i = 0; i < people.size(); ++i) {
      if (!whole[i]) continue;
      // The nearest candidate, accepted or not: where was this person lost?
      const vision_people::PersonCandidate* best = nullptr;
      double best_d = 1e9;
      for (const auto* list : {&result.people, &result.rejected}) {
        for (const auto& c : *list) {
          const double d = (on_floor(c.position_camera) - people[i].position).norm();
          if (d < best_d) {
            best_d = d;
            best = &c;
          }
        }
      }
      const auto& box = view.person_box[i];
      printf("  person %zu range %.2f px %5d box %3d %3d %3d %3d %s%s", i,
             (people[i].position - map_from_camera.translation().head<2>()).norm(),
             view.person_pixels[i], box[0], box[1], box[2], box[3], hit[i] ? "FOUND" : "lost ",
             confirmed_hit[i] ? "+conf " : "      ");
      if (best) {
        printf("cand d %.2f ", best_d);
        PrintCandidate(*best);
      } else {
        printf("no candidate within reach (clusters %d)\n", result.stats.num_clusters);
      }
    }
    // Candidates near nobody: accepted ones are false positives.
    for (const auto* list : {&result.people, &result.rejected}) {
      for (const auto& c : *list) {
        const Eigen::Vector2d xy = on_floor(c.position_camera);
        bool near_person = false;
        for (const auto& p : people) near_person = near_person || (xy - p.position).norm() <= 0.5;
        if (near_person) continue;
        printf("  other at %.2f %.2f %s ", xy.x(), xy.y(),
               c.accepted ? "FALSE-POSITIVE" : "rejected");
        PrintCandidate(c);
      }
    }
  }
  fig.detect_cpu_ms_mean = fig.frames ? cpu_sum / fig.frames : 0.0;
  return fig;
}

}  // namespace sim_vision
}  // namespace sarmap
