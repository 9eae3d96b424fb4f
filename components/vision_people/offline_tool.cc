// sarmap-vision-people-offline: runs the people detector on organized PCD files (x y z
// [rgb|rgba]) and prints every candidate with its features and decision.
#include <cmath>
#include <cstdio>
#include <fstream>

#include "common/args.h"
#include "common/options.h"
#include "vision_people/pcd_frame.h"
#include "vision_people/vision_people_options.h"

using namespace sarmap;
using namespace sarmap::vision_people;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-vision-people-offline", [&] {
    common::ArgParser parser("sarmap-vision-people-offline",
                             "Runs the RGB-D people detector on organized PCD files and prints the\n"
                             "candidates (accepted and rejected) with their features.");
    common::NodeArgs node_args;
    parser.AddNodeOptions(&node_args);
    std::vector<std::string> files;
    bool no_color = false;
    parser.AddSwitch("--no-color", &no_color, "ignore the colour (depth-only path)");
    std::string dump;
    parser.AddFlag("--dump", &dump, "write <prefix>_depth.pgm and <prefix>_rgb.ppm with candidate boxes");
    parser.AddRest("pcd", &files, "PCD files");
    if (!parser.Parse(argc, argv)) return 0;
    const auto options = common::LoadOptions<VisionPeopleOptions>(node_args.config_path, node_args.overrides);
    if (node_args.print_config) {
      fputs(common::OptionsToYaml(options, true).c_str(), stdout);
      return 0;
    }
    PeopleDetector detector(options.detector, InitialGround(options),
                            MakeHogClassifier(options.detector.color));
    for (const auto& path : files) {
      RgbdFrame frame;
      std::string error;
      if (!LoadPcdFrame(path, PinholeIntrinsics(), &frame, &error)) {
        fprintf(stderr, "%s\n", error.c_str());
        return 1;
      }
      if (no_color) frame.rgb.clear();
      const DetectionResult r = detector.Detect(frame, &error);
      printf("%s: %d people; points %d voxels %d floor voxels %d (refined %d) n=(%.4f %.4f %.4f) d=%.3f "
             "clusters %d candidates %d colour %s (mean %.0f std %.0f)%s%s\n",
             path.c_str(), static_cast<int>(r.people.size()), r.stats.num_points, r.stats.num_voxels,
             r.stats.num_ground_voxels, r.stats.ground_refined, r.ground.normal.x(), r.ground.normal.y(),
             r.ground.normal.z(), r.ground.offset, r.stats.num_clusters, r.stats.num_candidates,
             ColorStateName(r.stats.color_state), r.stats.color_mean, r.stats.color_std,
             error.empty() ? "" : " warning: ", error.c_str());
      if (!dump.empty()) {
        std::vector<uint8_t> grey(frame.width * frame.height), rgb(frame.width * frame.height * 3, 0);
        for (int i = 0; i < frame.width * frame.height; ++i) {
          const float z = frame.xyz[3 * i + 2];
          grey[i] = std::isfinite(z) ? static_cast<uint8_t>(std::min(255.0f, z * 32)) : 0;
          for (int c = 0; c < 3; ++c) rgb[3 * i + c] = frame.has_color() ? frame.rgb[3 * i + c] : grey[i];
        }
        auto box = [&](const PersonCandidate& c, uint8_t r, uint8_t g) {
          const double h = c.box_v_bottom - c.box_v_top;
          for (int v = static_cast<int>(c.box_v_top); v <= static_cast<int>(c.box_v_bottom); ++v) {
            for (int u = static_cast<int>(c.box_u_center - h / 4); u <= static_cast<int>(c.box_u_center + h / 4); ++u) {
              if (u < 0 || v < 0 || u >= frame.width || v >= frame.height) continue;
              const bool edge = v == static_cast<int>(c.box_v_top) || v == static_cast<int>(c.box_v_bottom) ||
                                u == static_cast<int>(c.box_u_center - h / 4) || u == static_cast<int>(c.box_u_center + h / 4);
              if (!edge) continue;
              uint8_t* p = &rgb[3 * (v * frame.width + u)];
              p[0] = r; p[1] = g; p[2] = 0;
            }
          }
        };
        for (const auto& c : r.people) box(c, 0, 255);
        for (const auto& c : r.rejected) box(c, 255, 0);
        std::ofstream(dump + "_rgb.ppm", std::ios::binary) << "P6\n" << frame.width << " " << frame.height << "\n255\n"
            << std::string(rgb.begin(), rgb.end());
      }
      for (const auto* list : {&r.people, &r.rejected}) {
        for (const auto& c : *list) {
          printf("  %s pos (%.2f %.2f %.2f) H %.2f bottom %.2f width %.2f depth %.2f head %.2f/%.2f prom %.2f areas %.3f/%.3f "
                 "fill %.2f visible %.2f%s voxels %d | depth %.2f hog %s %.2f conf %.2f box u %.0f v %.0f..%.0f\n",
                 c.accepted ? "PERSON" : "reject", c.position_camera.x(), c.position_camera.y(),
                 c.position_camera.z(), c.height_m, c.bottom_m, c.width_m, c.depth_extent_m,
                 c.head_width_m, c.shoulder_width_m, c.head_prominence_m, c.head_area_m2, c.shoulder_area_m2, c.fill, c.visible_fraction, c.truncated_top ? " (top cut)" : "", c.num_voxels,
                 c.depth_score, c.hog_used ? "yes" : "no", c.hog_score, c.confidence, c.box_u_center,
                 c.box_v_top, c.box_v_bottom);
        }
      }
    }
    return 0;
  });
}
