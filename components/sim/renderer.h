#pragma once
// A Kinect-like RGB-D camera rendered by a z-buffer rasteriser of planar convex polygons
// (walls, glass, boxes, table tops and legs, people). Two depth buffers: one for what
// returns infrared (the depth image: glass does not, a person's photo billboard does not,
// the person's body blocks do) and one for what is seen in colour (glass is blended on top,
// the person is the photo billboard). Shading is deferred: the raster pass writes only a
// depth and a polygon index per pixel, so overdraw costs little.
//
// Depth model (per valid pixel, z along the optical axis):
//   d = b f / z + N(0, (k b f)^2)       noise in disparity: sigma_z = k z^2 (growing with range^2)
//   d_q = round(d * s) / s, z_q = b f / d_q   disparity quantisation (1/s px)
// and 0 (invalid) outside [min_range, max_range], outside the depth field of view, beyond the
// grazing-angle limit, in projector shadows and for a random `dropout` fraction.

#include <cstdint>
#include <memory>
#include <vector>

#include "common/transform.h"
#include "sim/appearance.h"
#include "sim/sim_options.h"
#include "sim/world.h"

namespace sarmap {
namespace sim {

struct Intrinsics {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

struct RenderOutput {
  std::vector<uint16_t> depth_mm;  // width*height, 0 = invalid
  std::vector<uint8_t> rgb;        // width*height*3
  std::vector<float> true_depth_m; // noise-free depth of the IR buffer (inf: nothing), for tests
  bool fill_true_depth = true;     // false skips true_depth_m
  // Per person (world order): visible body pixels and their bounding box (x0, y0, x1, y1),
  // from the IR buffer (the body, not the photo margin).
  std::vector<int> person_pixels;
  std::vector<std::array<int, 4>> person_box;
};

class Renderer {
 public:
  Renderer(const CameraOptions& options, uint64_t seed);
  ~Renderer();

  // Builds the static scene and the people (appearances indexed by Person::appearance or id).
  void SetWorld(const World& world, const std::vector<Appearance>* appearances);
  // Renders the view of a camera whose optical frame (z forward, x right, y down) is at
  // map_from_camera.
  void Render(const common::Rigid3d& map_from_camera, RenderOutput* out);

  const Intrinsics& intrinsics() const { return intrinsics_; }
  // CPU seconds spent in the rasteriser and the colour and depth passes (benchmark).
  struct Timing {
    double raster_s = 0, colour_s = 0, depth_s = 0;
    long frames = 0;
  };
  const Timing& timing() const { return timing_; }

 private:
  struct Polygon;
  void Rasterise(const Polygon& poly, int index, const std::vector<Eigen::Vector3f>& cam_vertices);
  void AddQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
               const Eigen::Vector3d& d, const Rgb& colour, int flags, int person);
  void AddBox(const Eigen::Vector2d& centre, double yaw, const Eigen::Vector3d& size, double base,
              const Rgb& colour, int flags, int person, bool bottom);

  CameraOptions options_;
  Intrinsics intrinsics_;
  bool lights_on_ = true;
  float background_[3] = {0.08f, 0.08f, 0.09f};
  std::vector<Polygon> polygons_;
  std::vector<Eigen::Vector3f> vertices_;  // map frame, 4 per polygon
  std::vector<Person> people_;
  const std::vector<Appearance>* appearances_ = nullptr;
  int first_billboard_ = 0;
  // Buffers.
  std::vector<float> ir_z_, color_z_;
  std::vector<int32_t> ir_id_, color_id_;
  std::vector<uint8_t> glass_layers_;
  std::vector<uint8_t> depth_fov_;  // 1 where the depth camera sees
  std::vector<float> ray_inv_norm_;
  // Fast noise: a table of N(0,1) samples read at random offsets.
  std::vector<float> normal_table_;
  std::vector<int8_t> noise_i8_;      // N(0,1) * 32
  std::vector<int8_t> colour_noise_i8_;  // N(0,1) * colour sigma, 8-bit units
  std::vector<uint16_t> uniform_u16_;  // uniform 0..65535
  uint64_t rng_state_;
  Timing timing_;
};

}  // namespace sim
}  // namespace sarmap
