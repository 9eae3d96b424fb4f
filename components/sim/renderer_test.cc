#include "sim/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sarmap {
namespace sim {
namespace {

// The camera optical frame (z forward, x right, y down) looking along +x of the map at height h.
common::Rigid3d CameraAt(double x, double y, double h) {
  const Eigen::Quaterniond r = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX());
  return common::Rigid3d(Eigen::Vector3d(x, y, h), r);
}

Wall WallAcross(double x, bool glass = false) {
  Wall w;
  w.from = Eigen::Vector2d(x, -6);
  w.to = Eigen::Vector2d(x, 6);
  w.height_m = 3.0;
  w.thickness_m = glass ? 0.02 : 0.1;
  w.glass = glass;
  if (glass) w.colour = Rgb{0.75f, 0.85f, 0.9f};
  return w;
}

// Depth (m) of the valid pixels in a square patch around the image centre.
std::vector<double> CentrePatch(const RenderOutput& out, const Intrinsics& in, int half, int* invalid) {
  std::vector<double> z;
  *invalid = 0;
  for (int j = in.height / 2 - half; j < in.height / 2 + half; ++j) {
    for (int i = in.width / 2 - half; i < in.width / 2 + half; ++i) {
      const uint16_t d = out.depth_mm[static_cast<size_t>(j) * in.width + i];
      if (d == 0) ++*invalid;
      else z.push_back(d / 1000.0);
    }
  }
  return z;
}

TEST(RendererTest, WallAtKnownRangeReadsThatDepthWithinTheNoiseModel) {
  CameraOptions options;
  World world;
  world.walls.push_back(WallAcross(3.05));  // front face at x = 3.0
  Renderer renderer(options, 7);
  renderer.SetWorld(world, nullptr);
  RenderOutput out;
  renderer.Render(CameraAt(0, 0, 1.2), &out);
  const Intrinsics& in = renderer.intrinsics();
  EXPECT_NEAR(out.true_depth_m[static_cast<size_t>(in.height / 2) * in.width + in.width / 2], 3.0, 1e-4);
  int invalid = 0;
  const std::vector<double> z = CentrePatch(out, in, 20, &invalid);
  // Model: sigma = k z^2 plus disparity quantisation (step z^2 / (b f s)).
  const double sigma = options.depth_noise_k * 9.0;
  const double step = 9.0 / (options.baseline_m * options.depth_fx_px * options.disparity_subpixel);
  const double expected_std = std::sqrt(sigma * sigma + step * step / 12);
  const double mean = std::accumulate(z.begin(), z.end(), 0.0) / z.size();
  double var = 0;
  for (double v : z) var += (v - mean) * (v - mean);
  const double std_dev = std::sqrt(var / z.size());
  std::printf("wall at 3.0 m: mean %.4f m, std %.4f m (model %.4f), invalid %d of 1600\n", mean, std_dev,
              expected_std, invalid);
  EXPECT_NEAR(mean, 3.0, 3 * expected_std / std::sqrt(z.size()) + 0.003);
  EXPECT_GT(std_dev, 0.6 * expected_std);
  EXPECT_LT(std_dev, 1.5 * expected_std);
  EXPECT_LT(invalid, 1600 * 0.02);
  for (double v : z) EXPECT_LT(std::abs(v - 3.0), 5 * sigma + step);
  // Disparity quantisation: only a handful of distinct depths.
  std::vector<double> levels = z;
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end(), [](double a, double b) { return std::abs(a - b) < 5e-4; }),
               levels.end());
  EXPECT_LT(levels.size(), 15u);
}

TEST(RendererTest, RangeLimitsAndDepthFieldOfView) {
  CameraOptions options;
  World world;
  world.walls.push_back(WallAcross(5.05));  // beyond 4.6 m: no reading
  Renderer renderer(options, 7);
  renderer.SetWorld(world, nullptr);
  RenderOutput out;
  renderer.Render(CameraAt(0, 0, 1.2), &out);
  int invalid = 0;
  const auto z = CentrePatch(out, renderer.intrinsics(), 10, &invalid);
  EXPECT_EQ(invalid, 400);
  // Wall at 2 m: the image's left and right edge columns lie outside the 58 deg depth view.
  World near;
  near.walls.push_back(WallAcross(2.05));
  renderer.SetWorld(near, nullptr);
  renderer.Render(CameraAt(0, 0, 1.2), &out);
  const Intrinsics& in = renderer.intrinsics();
  const size_t row = static_cast<size_t>(in.height / 2) * in.width;
  EXPECT_EQ(out.depth_mm[row + 1], 0);
  EXPECT_EQ(out.depth_mm[row + in.width - 2], 0);
  EXPECT_GT(out.depth_mm[row + 30], 0);
}

TEST(RendererTest, OcclusionGlassAndTable) {
  CameraOptions options;
  options.dropout = 0;
  World world;
  world.walls.push_back(WallAcross(4.05));  // background wall at 4.0
  Box box;
  box.centre = Eigen::Vector2d(2.2, 0);
  box.size_m = Eigen::Vector3d(0.4, 0.6, 2.0);  // front face at 2.0
  world.boxes.push_back(box);
  Renderer renderer(options, 3);
  renderer.SetWorld(world, nullptr);
  RenderOutput out;
  renderer.Render(CameraAt(0, 0, 1.2), &out);
  const Intrinsics& in = renderer.intrinsics();
  const size_t centre = static_cast<size_t>(in.height / 2) * in.width + in.width / 2;
  EXPECT_NEAR(out.depth_mm[centre] / 1000.0, 2.0, 0.05);  // the box hides the wall
  EXPECT_NEAR(out.depth_mm[centre - 150] / 1000.0, 4.0, 0.25);  // beside it: the wall

  // A glass pane at 1.5 m: depth passes through to the box, colour shows a tint.
  World glassy = world;
  glassy.walls.push_back(WallAcross(1.5, true));
  RenderOutput with_glass;
  renderer.SetWorld(glassy, nullptr);
  renderer.Render(CameraAt(0, 0, 1.2), &with_glass);
  EXPECT_NEAR(with_glass.true_depth_m[centre], 2.0, 1e-3);
  EXPECT_NEAR(with_glass.depth_mm[centre] / 1000.0, 2.0, 0.05);
  double colour_change = 0;
  for (size_t p = 0; p < out.rgb.size(); ++p) colour_change += std::abs(out.rgb[p] - with_glass.rgb[p]);
  colour_change /= out.rgb.size();
  EXPECT_GT(colour_change, 3.0);  // visible in colour
  // Glass with nothing within range behind it: no return at all.
  World only_glass;
  only_glass.walls.push_back(WallAcross(1.5, true));
  only_glass.walls.push_back(WallAcross(8.0));
  renderer.SetWorld(only_glass, nullptr);
  renderer.Render(CameraAt(0, 0, 1.2), &out);
  EXPECT_EQ(out.depth_mm[centre], 0);

  // A table: its top is seen, the open space beneath shows the wall behind.
  World table_world;
  table_world.walls.push_back(WallAcross(3.55));
  Table table;
  table.centre = Eigen::Vector2d(2.0, 0);
  table.size_m = Eigen::Vector2d(0.8, 1.6);
  table.height_m = 0.75;
  table_world.tables.push_back(table);
  renderer.SetWorld(table_world, nullptr);
  renderer.Render(CameraAt(0, 0, 0.4), &out);  // camera below the table top
  EXPECT_NEAR(out.true_depth_m[centre], 3.5, 1e-3);  // under the table
  // The row that looks at height 0.73 m at the table's front edge (x = 1.6) sees the top.
  const int row_top = static_cast<int>(std::lround(in.cy - in.fy * (0.73 - 0.4) / 1.6));
  EXPECT_NEAR(out.true_depth_m[static_cast<size_t>(row_top) * in.width + in.width / 2], 1.6, 0.01);
}

TEST(RendererTest, LightsOffGivesADarkNoisyImage) {
  CameraOptions options;
  World world;
  world.walls.push_back(WallAcross(3.05));
  Renderer renderer(options, 5);
  renderer.SetWorld(world, nullptr);
  RenderOutput lit, dark;
  renderer.Render(CameraAt(0, 0, 1.2), &lit);
  world.lights_on = false;
  renderer.SetWorld(world, nullptr);
  renderer.Render(CameraAt(0, 0, 1.2), &dark);
  auto stats = [](const std::vector<uint8_t>& rgb, double* mean, double* local_noise) {
    double s = 0, d = 0;
    for (size_t p = 0; p < rgb.size(); ++p) s += rgb[p];
    for (size_t p = 3; p < rgb.size(); ++p) d += std::abs(rgb[p] - rgb[p - 3]);
    *mean = s / rgb.size();
    *local_noise = d / rgb.size();
  };
  double lit_mean, lit_noise, dark_mean, dark_noise;
  stats(lit.rgb, &lit_mean, &lit_noise);
  stats(dark.rgb, &dark_mean, &dark_noise);
  std::printf("lit mean %.1f noise %.2f, dark mean %.1f noise %.2f\n", lit_mean, lit_noise, dark_mean, dark_noise);
  EXPECT_LT(dark_mean, 0.2 * lit_mean);
  EXPECT_GT(dark_noise / std::max(dark_mean, 1.0), 3 * lit_noise / lit_mean);  // noise dominates
  // Depth does not care about light.
  int same = 0, valid = 0;
  for (size_t p = 0; p < lit.depth_mm.size(); ++p) {
    valid += lit.depth_mm[p] > 0;
    same += lit.depth_mm[p] > 0 && dark.depth_mm[p] > 0;
  }
  EXPECT_GT(same, 0.95 * valid);
}

}  // namespace
}  // namespace sim
}  // namespace sarmap
