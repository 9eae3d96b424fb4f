// sarmap-vision-people-offline: runs the people detector on organized PCD files (x y z
// [rgb|rgba]) or depth images (16-bit PNG/PGM/TIFF, with the colour image beside them when
// there is one) and prints every candidate with its features and decision.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "common/args.h"
#include "common/options.h"
#include "vision_people/image_frame.h"
#include "vision_people/pcd_frame.h"
#include "vision_people/vision_people_options.h"

using namespace sarmap;
using namespace sarmap::vision_people;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-vision-people-offline", [&] {
    common::ArgParser parser(
        "sarmap-vision-people-offline",
        "Runs the RGB-D people detector on organized PCD files and prints the\n"
        "candidates (accepted and rejected) with their features.");
    common::NodeArgs node_args;
    parser.AddNodeOptions(&node_args);
    std::vector<std::string> files;
    bool no_color = false;
    parser.AddSwitch("--no-color", &no_color, "ignore the colour (depth-only path)");
    std::string dump;
    parser.AddFlag("--dump", &dump,
                   "write <prefix>_depth.pgm and <prefix>_rgb.ppm with candidate boxes");
    std::string depth_unit = "0.001", intrinsics_text = "525,525,319.5,239.5";
    parser.AddFlag("--depth-unit-m", &depth_unit,
                   "depth images: metres per stored unit (TUM: 0.0002)");
    parser.AddFlag("--intrinsics", &intrinsics_text, "fx,fy,cx,cy of the (registered) depth image");
    bool sequence = false;
    parser.AddSwitch("--sequence", &sequence,
                     "the files are one sequence (30 Hz): keep the floor track between them");
    parser.AddRest("files", &files, "PCD files or depth images");
    if (!parser.Parse(argc, argv)) return 0;
    const auto options =
        common::LoadOptions<VisionPeopleOptions>(node_args.config_path, node_args.overrides);
    if (node_args.print_config) {
      fputs(common::OptionsToYaml(options, true).c_str(), stdout);
      return 0;
    }
    PinholeIntrinsics intrinsics;
    if (sscanf(intrinsics_text.c_str(), "%lf,%lf,%lf,%lf", &intrinsics.fx, &intrinsics.fy,
               &intrinsics.cx, &intrinsics.cy) != 4) {
      fprintf(stderr, "--intrinsics wants fx,fy,cx,cy, not '%s'\n", intrinsics_text.c_str());
      return 2;
    }
    const double unit_m = std::atof(depth_unit.c_str());
    if (!(unit_m > 0)) {
      fprintf(stderr, "--depth-unit-m must be positive, not '%s'\n", depth_unit.c_str());
      return 2;
    }
    PeopleDetector detector(options.detector, InitialGround(options),
                            MakeHogClassifier(options.detector.color));
    int64_t index = 0;
    for (const auto& path : files) {
      RgbdFrame frame;
      std::string error;
      const bool pcd = path.size() > 4 && path.substr(path.size() - 4) == ".pcd";
      const bool ok = pcd ? LoadPcdFrame(path, intrinsics, &frame, &error)
                          : LoadDepthImageFrame(path, no_color ? "" : FindColorImage(path), unit_m,
                                                intrinsics, &frame, &error);
      if (!ok) {
        fprintf(stderr, "%s\n", error.c_str());
        return 1;
      }
      frame.utime = index++ * 33333;
      if (!sequence) detector.ResetGround();
      if (no_color) frame.rgb.clear();
      const DetectionResult r = detector.Detect(frame, &error);
      printf(
          "%s: %d people; points %d voxels %d floor points %d voxels %d (found %d) n=(%.4f %.4f "
          "%.4f) d=%.3f "
          "camera height %.2f m tilt down %.1f deg roll %.1f deg%s "
          "clusters %d candidates %d colour %s (mean %.0f std %.0f)%s%s\n",
          path.c_str(), static_cast<int>(r.people.size()), r.stats.num_points, r.stats.num_voxels,
          r.stats.num_ground_points, r.stats.num_ground_voxels, r.stats.ground_refined,
          r.ground.normal.x(), r.ground.normal.y(), r.ground.normal.z(), r.ground.offset,
          r.camera.height_m, r.camera.tilt_down_rad * 180 / M_PI, r.camera.roll_rad * 180 / M_PI,
          r.stats.mounting_mismatch ? " (differs from the mounting file)" : "",
          r.stats.num_clusters, r.stats.num_candidates, ColorStateName(r.stats.color_state),
          r.stats.color_mean, r.stats.color_std, error.empty() ? "" : " warning: ", error.c_str());
      if (!dump.empty()) {
        std::vector<uint8_t> grey(frame.width * frame.height),
            rgb(frame.width * frame.height * 3, 0);
        for (int i = 0; i < frame.width * frame.height; ++i) {
          const float z = frame.xyz[3 * i + 2];
          grey[i] = std::isfinite(z) ? static_cast<uint8_t>(std::min(255.0f, z * 32)) : 0;
          for (int c = 0; c < 3; ++c)
            rgb[3 * i + c] = frame.has_color() ? frame.rgb[3 * i + c] : grey[i];
        }
        auto box = [&](const PersonCandidate& c, uint8_t r, uint8_t g) {
          const double h = c.box_v_bottom - c.box_v_top;
          for (int v = static_cast<int>(c.box_v_top); v <= static_cast<int>(c.box_v_bottom); ++v) {
            for (int u = static_cast<int>(c.box_u_center - h / 4);
                 u <= static_cast<int>(c.box_u_center + h / 4); ++u) {
              if (u < 0 || v < 0 || u >= frame.width || v >= frame.height) continue;
              const bool edge = v == static_cast<int>(c.box_v_top) ||
                                v == static_cast<int>(c.box_v_bottom) ||
                                u == static_cast<int>(c.box_u_center - h / 4) ||
                                u == static_cast<int>(c.box_u_center + h / 4);
              if (!edge) continue;
              uint8_t* p = &rgb[3 * (v * frame.width + u)];
              p[0] = r;
              p[1] = g;
              p[2] = 0;
            }
          }
        };
        for (const auto& c : r.people) box(c, 0, 255);
        for (const auto& c : r.rejected) box(c, 255, 0);
        std::ofstream(dump + "_rgb.ppm", std::ios::binary)
            << "P6\n"
            << frame.width << " " << frame.height << "\n255\n"
            << std::string(rgb.begin(), rgb.end());
      }
      for (const auto* list : {&r.people, &r.rejected}) {
        for (const auto& c : *list) {
          printf("  %s box u %.0f v %.0f..%.0f\n", DescribeCandidate(c).c_str(), c.box_u_center,
                 c.box_v_top, c.box_v_bottom);
        }
      }
    }
    return 0;
  });
}
