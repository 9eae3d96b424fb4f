#include "sim/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <time.h>

namespace sarmap {
namespace sim {
namespace {

enum Flags { kIr = 1, kColour = 2, kGlass = 4, kTwoSided = 8, kBillboard = 16, kLyingBillboard = 32 };
constexpr float kNear = 0.05f;
constexpr int kNormalTableSize = 1 << 16;
constexpr size_t kNoiseSlack = 1 << 14;

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

inline uint64_t XorShift(uint64_t* s) {
  uint64_t x = *s;
  x ^= x << 13;
  x ^= x >> 7;
  x ^= x << 17;
  *s = x;
  return x;
}

// Light direction (map frame) for the lit scene: mostly from above.
const Eigen::Vector3f kLight = Eigen::Vector3f(0.4f, 0.25f, 0.88f).normalized();

}  // namespace

struct Renderer::Polygon {
  int flags = 0;
  int person = -1;  // index into people_, -1 for the static scene
  Rgb colour;
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();  // map frame
  float shade[3] = {0, 0, 0};
  // Per frame, camera frame: plane n.X = d, texture axes (column, row fractions).
  Eigen::Vector3f n_cam = Eigen::Vector3f::Zero();
  float d_cam = 0;
  Eigen::Vector3f tex_origin = Eigen::Vector3f::Zero(), tex_s = Eigen::Vector3f::Zero(), tex_t = Eigen::Vector3f::Zero();
  int appearance = 0;
};

Renderer::Renderer(const CameraOptions& options, uint64_t seed)
    : options_(options), rng_state_(seed * 0x9E3779B97F4A7C15ull + 0x1234567ull) {
  if (rng_state_ == 0) rng_state_ = 1;
  intrinsics_.width = options.width;
  intrinsics_.height = options.height;
  intrinsics_.cx = (options.width - 1) / 2.0;
  intrinsics_.cy = (options.height - 1) / 2.0;
  intrinsics_.fx = (options.width / 2.0) / std::tan(options.color_hfov_deg * M_PI / 360.0);
  intrinsics_.fy = (options.height / 2.0) / std::tan(options.color_vfov_deg * M_PI / 360.0);
  const size_t n = static_cast<size_t>(options.width) * options.height;
  ir_z_.resize(n);
  color_z_.resize(n);
  ir_id_.resize(n);
  color_id_.resize(n);
  glass_layers_.resize(n);
  depth_fov_.resize(n);
  ray_inv_norm_.resize(n);
  const double tan_h = std::tan(options.depth_hfov_deg * M_PI / 360.0);
  const double tan_v = std::tan(options.depth_vfov_deg * M_PI / 360.0);
  for (int j = 0; j < options.height; ++j) {
    for (int i = 0; i < options.width; ++i) {
      const double rx = (i - intrinsics_.cx) / intrinsics_.fx, ry = (j - intrinsics_.cy) / intrinsics_.fy;
      const size_t p = static_cast<size_t>(j) * options.width + i;
      depth_fov_[p] = std::abs(rx) <= tan_h && std::abs(ry) <= tan_v;
      ray_inv_norm_[p] = static_cast<float>(1.0 / std::sqrt(rx * rx + ry * ry + 1.0));
    }
  }
  std::mt19937_64 gen(seed + 77);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  normal_table_.resize(kNormalTableSize);
  for (float& v : normal_table_) v = normal(gen);
  // Noise read sequentially from a random offset each frame: far cheaper than drawing
  // 1.2 million normal samples per frame, and still different from frame to frame.
  noise_i8_.resize(3 * n + kNoiseSlack);
  for (int8_t& v : noise_i8_) v = static_cast<int8_t>(std::clamp(std::lround(normal(gen) * 32.0f), -127L, 127L));
  colour_noise_i8_.resize(noise_i8_.size());  // lit until SetWorld says otherwise
  for (size_t q = 0; q < noise_i8_.size(); ++q) {
    colour_noise_i8_[q] = static_cast<int8_t>(std::lround(noise_i8_[q] / 32.0f * options.color_noise * 255.0f));
  }
  std::uniform_int_distribution<int> uniform16(0, 65535);
  uniform_u16_.resize(n + kNoiseSlack);
  for (uint16_t& v : uniform_u16_) v = static_cast<uint16_t>(uniform16(gen));
}

Renderer::~Renderer() = default;

void Renderer::AddQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d, const Rgb& colour, int flags, int person) {
  Polygon poly;
  poly.flags = flags;
  poly.person = person;
  poly.colour = colour;
  poly.normal = (b - a).cross(c - a).normalized().cast<float>();
  // Lambert with ambient, the light from above; two-sided faces take the brighter side.
  float lambert = poly.normal.dot(kLight);
  if (flags & kTwoSided) lambert = std::abs(lambert);
  const float light = 0.55f + 0.45f * std::max(0.0f, lambert);
  poly.shade[0] = colour.r * light;
  poly.shade[1] = colour.g * light;
  poly.shade[2] = colour.b * light;
  polygons_.push_back(poly);
  for (const auto* v : {&a, &b, &c, &d}) vertices_.push_back(v->cast<float>());
}

// An oriented box: faces counter-clockwise seen from outside (outward normals).
void Renderer::AddBox(const Eigen::Vector2d& centre, double yaw, const Eigen::Vector3d& size,
                      double base, const Rgb& colour, int flags, int person, bool bottom) {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
  auto corner = [&](double sx, double sy, double z) {
    const Eigen::Vector2d p = centre + ax * (sx * size.x() / 2) + ay * (sy * size.y() / 2);
    return Eigen::Vector3d(p.x(), p.y(), z);
  };
  const double z0 = base, z1 = base + size.z();
  const Eigen::Vector3d p000 = corner(-1, -1, z0), p100 = corner(1, -1, z0), p110 = corner(1, 1, z0),
                        p010 = corner(-1, 1, z0), p001 = corner(-1, -1, z1), p101 = corner(1, -1, z1),
                        p111 = corner(1, 1, z1), p011 = corner(-1, 1, z1);
  AddQuad(p000, p100, p101, p001, colour, flags, person);  // -y side
  AddQuad(p100, p110, p111, p101, colour, flags, person);  // +x
  AddQuad(p110, p010, p011, p111, colour, flags, person);  // +y
  AddQuad(p010, p000, p001, p011, colour, flags, person);  // -x
  AddQuad(p001, p101, p111, p011, colour, flags, person);  // top
  if (bottom) AddQuad(p000, p010, p110, p100, colour, flags, person);
}

void Renderer::SetWorld(const World& world, const std::vector<Appearance>* appearances) {
  polygons_.clear();
  vertices_.clear();
  lights_on_ = world.lights_on;
  // Colour noise in 8-bit units for this lighting: N(0,1) * sigma * 255.
  const float sigma = static_cast<float>((lights_on_ ? options_.color_noise : options_.dark_noise) * 255.0);
  colour_noise_i8_.resize(noise_i8_.size());
  for (size_t q = 0; q < noise_i8_.size(); ++q) {
    colour_noise_i8_[q] = static_cast<int8_t>(std::clamp(std::lround(noise_i8_[q] / 32.0f * sigma), -127L, 127L));
  }
  if (world.ceiling_height_m > 0) {
    background_[0] = 0.08f, background_[1] = 0.08f, background_[2] = 0.09f;
  } else {
    background_[0] = 0.62f, background_[1] = 0.68f, background_[2] = 0.76f;  // overcast sky
  }
  appearances_ = appearances;
  people_ = world.people;
  // Floor (and ceiling) over everything, with a wide margin for open areas.
  Eigen::Vector2d lo(-5, -5), hi(5, 5);
  for (const Wall& w : world.walls) {
    lo = lo.cwiseMin(w.from).cwiseMin(w.to);
    hi = hi.cwiseMax(w.from).cwiseMax(w.to);
  }
  for (const Person& p : world.people) {
    lo = lo.cwiseMin(p.position);
    hi = hi.cwiseMax(p.position);
  }
  lo.array() -= 30;
  hi.array() += 30;
  AddQuad({lo.x(), lo.y(), 0}, {hi.x(), lo.y(), 0}, {hi.x(), hi.y(), 0}, {lo.x(), hi.y(), 0},
          world.floor_colour, kIr | kColour, -1);
  if (world.ceiling_height_m > 0) {
    const double h = world.ceiling_height_m;
    AddQuad({lo.x(), lo.y(), h}, {lo.x(), hi.y(), h}, {hi.x(), hi.y(), h}, {hi.x(), lo.y(), h},
            world.ceiling_colour, kIr | kColour, -1);
  }
  for (const Wall& w : world.walls) {
    const Eigen::Vector2d d = w.to - w.from;
    const Eigen::Vector2d mid = (w.from + w.to) / 2;
    const double yaw = std::atan2(d.y(), d.x());
    if (w.glass) {
      // Both faces of the pane: seen in colour as a faint tint, no infrared return.
      const Eigen::Vector2d nrm = Eigen::Vector2d(-d.y(), d.x()).normalized() * (w.thickness_m / 2);
      for (double side : {1.0, -1.0}) {
        const Eigen::Vector2d a = w.from + side * nrm, b = w.to + side * nrm;
        AddQuad({a.x(), a.y(), w.base_m}, {b.x(), b.y(), w.base_m}, {b.x(), b.y(), w.base_m + w.height_m},
                {a.x(), a.y(), w.base_m + w.height_m}, w.colour, kGlass | kTwoSided, -1);
      }
    } else {
      AddBox(mid, yaw, {d.norm() + w.thickness_m, w.thickness_m, w.height_m}, w.base_m, w.colour,
             kIr | kColour, -1, w.base_m > 0);
    }
  }
  for (const Box& b : world.boxes) {
    AddBox(b.centre, b.yaw_rad, b.size_m, b.base_m, b.colour, kIr | kColour, -1, b.base_m > 0);
  }
  for (const Table& t : world.tables) {
    AddBox(t.centre, t.yaw_rad, {t.size_m.x(), t.size_m.y(), t.top_thickness_m},
           t.height_m - t.top_thickness_m, t.colour, kIr | kColour, -1, true);
    const Eigen::Vector2d ax(std::cos(t.yaw_rad), std::sin(t.yaw_rad)), ay(-ax.y(), ax.x());
    const double leg_h = t.height_m - t.top_thickness_m;
    for (double sx : {-1.0, 1.0}) {
      for (double sy : {-1.0, 1.0}) {
        const Eigen::Vector2d c = t.centre + ax * sx * (t.size_m.x() / 2 - t.leg_width_m) +
                                  ay * sy * (t.size_m.y() / 2 - t.leg_width_m);
        AddBox(c, t.yaw_rad, {t.leg_width_m, t.leg_width_m, leg_h}, 0.0, t.colour, kIr | kColour, -1, false);
      }
    }
  }
  // People: body blocks return infrared (the depth image sees a body); the photo billboard
  // is what the colour camera sees.
  const Rgb skin{0.6f, 0.5f, 0.45f};
  for (size_t k = 0; k < people_.size(); ++k) {
    const Person& p = people_[k];
    const double s = p.height_m / 1.75;
    const int person = static_cast<int>(k);
    const Eigen::Vector2d fwd(std::cos(p.yaw_rad), std::sin(p.yaw_rad));
    switch (p.posture) {
      case Posture::kStanding:
        AddBox(p.position, p.yaw_rad, {0.22 * s, 0.36 * s, 0.85 * s}, 0.0, skin, kIr, person, false);
        AddBox(p.position, p.yaw_rad, {0.25 * s, 0.44 * s, 0.63 * s}, 0.85 * s, skin, kIr, person, true);
        AddBox(p.position, p.yaw_rad, {0.20 * s, 0.18 * s, 0.27 * s}, 1.48 * s, skin, kIr, person, true);
        break;
      case Posture::kSitting:
        AddBox(p.position + fwd * 0.2 * s, p.yaw_rad, {0.45 * s, 0.36 * s, 0.15 * s}, 0.45 * s, skin, kIr, person, true);
        AddBox(p.position + fwd * 0.4 * s, p.yaw_rad, {0.12 * s, 0.36 * s, 0.45 * s}, 0.0, skin, kIr, person, false);
        AddBox(p.position, p.yaw_rad, {0.25 * s, 0.44 * s, 0.6 * s}, 0.5 * s, skin, kIr, person, true);
        AddBox(p.position, p.yaw_rad, {0.20 * s, 0.18 * s, 0.27 * s}, 1.1 * s, skin, kIr, person, true);
        break;
      case Posture::kLying:
        // On the back, head along yaw: legs, chest (the highest part) and head differ in
        // height as a body's do (the depth image sees a body, not a crate).
        AddBox(p.position - fwd * 0.42 * s, p.yaw_rad, {0.91 * s, 0.34 * s, 0.15}, 0.0, skin, kIr, person, false);
        AddBox(p.position + fwd * 0.34 * s, p.yaw_rad, {0.62 * s, 0.44 * s, 0.24}, 0.0, skin, kIr, person, false);
        AddBox(p.position + fwd * 0.76 * s, p.yaw_rad, {0.22 * s, 0.18 * s, 0.19}, 0.0, skin, kIr, person, false);
        break;
    }
  }
  first_billboard_ = static_cast<int>(polygons_.size());
  for (size_t k = 0; k < people_.size(); ++k) {
    const Eigen::Vector3d z = Eigen::Vector3d::Zero();  // placed per frame
    AddQuad({0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, skin,
            kColour | kTwoSided | kBillboard | (people_[k].posture == Posture::kLying ? kLyingBillboard : 0),
            static_cast<int>(k));
    (void)z;
    const int count = appearances_ && !appearances_->empty() ? static_cast<int>(appearances_->size()) : 1;
    const int wanted = people_[k].appearance >= 0 ? people_[k].appearance : people_[k].id - 1;
    polygons_.back().appearance = ((wanted % count) + count) % count;
  }
}

void Renderer::Rasterise(const Polygon& poly, int index, const std::vector<Eigen::Vector3f>& cam) {
  const int W = intrinsics_.width, H = intrinsics_.height;
  const float fx = static_cast<float>(intrinsics_.fx), fy = static_cast<float>(intrinsics_.fy);
  const float cx = static_cast<float>(intrinsics_.cx), cy = static_cast<float>(intrinsics_.cy);
  // Clip against the near plane (Sutherland-Hodgman), then project.
  Eigen::Vector3f in[4] = {cam[4 * index], cam[4 * index + 1], cam[4 * index + 2], cam[4 * index + 3]};
  Eigen::Vector2f pts[8];
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3f& a = in[k];
    const Eigen::Vector3f& b = in[(k + 1) % 4];
    const bool a_in = a.z() >= kNear, b_in = b.z() >= kNear;
    if (a_in) pts[n++] = {fx * a.x() / a.z() + cx, fy * a.y() / a.z() + cy};
    if (a_in != b_in) {
      const float t = (kNear - a.z()) / (b.z() - a.z());
      const Eigen::Vector3f c = a + t * (b - a);
      pts[n++] = {fx * c.x() / kNear + cx, fy * c.y() / kNear + cy};
    }
  }
  if (n < 3) return;
  float vmin = pts[0].y(), vmax = pts[0].y(), umin = pts[0].x(), umax = pts[0].x();
  for (int k = 1; k < n; ++k) {
    vmin = std::min(vmin, pts[k].y());
    vmax = std::max(vmax, pts[k].y());
    umin = std::min(umin, pts[k].x());
    umax = std::max(umax, pts[k].x());
  }
  if (umax < 0 || umin > W - 1 || vmax < 0 || vmin > H - 1) return;
  const int j0 = std::max(0, static_cast<int>(std::ceil(vmin)));
  const int j1 = std::min(H - 1, static_cast<int>(std::floor(vmax)));
  // 1/z is affine in pixel coordinates on a plane: 1/z = A u + B v + C.
  const Eigen::Vector3f& nc = poly.n_cam;
  const float d = poly.d_cam;
  const float A = nc.x() / (fx * d), B = nc.y() / (fy * d);
  const float C = (nc.z() - nc.x() * cx / fx - nc.y() * cy / fy) / d;
  const bool ir = poly.flags & kIr, colour = poly.flags & kColour, glass = poly.flags & kGlass;
  for (int j = j0; j <= j1; ++j) {
    const float v = static_cast<float>(j);
    float xl = std::numeric_limits<float>::max(), xr = -std::numeric_limits<float>::max();
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2f& a = pts[k];
      const Eigen::Vector2f& b = pts[(k + 1) % n];
      if ((a.y() <= v && b.y() > v) || (b.y() <= v && a.y() > v) ||
          (a.y() == v && b.y() == v)) {
        if (a.y() == b.y()) {
          xl = std::min({xl, a.x(), b.x()});
          xr = std::max({xr, a.x(), b.x()});
        } else {
          const float x = a.x() + (v - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
          xl = std::min(xl, x);
          xr = std::max(xr, x);
        }
      }
    }
    if (xl > xr) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil(xl)));
    const int i1 = std::min(W - 1, static_cast<int>(std::floor(xr)));
    const size_t row = static_cast<size_t>(j) * W;
    float iz = A * i0 + B * v + C;
    for (int i = i0; i <= i1; ++i, iz += A) {
      const size_t p = row + i;
      if (glass) {
        if (iz > color_z_[p]) ++glass_layers_[p];
        continue;
      }
      if (ir && iz > ir_z_[p]) {
        ir_z_[p] = iz;
        ir_id_[p] = index;
      }
      if (colour && iz > color_z_[p]) {
        color_z_[p] = iz;
        color_id_[p] = index;
      }
    }
  }
}

void Renderer::Render(const common::Rigid3d& map_from_camera, RenderOutput* out) {
  const int W = intrinsics_.width, H = intrinsics_.height;
  const size_t N = static_cast<size_t>(W) * H;
  const Eigen::Matrix3f cam_R_map = map_from_camera.rotation().conjugate().toRotationMatrix().cast<float>();
  const Eigen::Vector3f cam_pos = map_from_camera.translation().cast<float>();

  // Billboards face the camera (about the vertical axis); lying people lie flat.
  for (size_t k = 0; k < people_.size(); ++k) {
    const int index = first_billboard_ + static_cast<int>(k);
    Polygon& poly = polygons_[index];
    const Person& p = people_[k];
    const Appearance* app = appearances_ && !appearances_->empty() ? &(*appearances_)[poly.appearance] : nullptr;
    const double frac = app ? app->person_bottom - app->person_top : 0.75;
    const double top_frac = app ? app->person_top : 0.125;
    const double aspect = app ? static_cast<double>(app->width) / app->height : 0.5;
    const double body = p.posture == Posture::kSitting ? 0.8 * p.height_m : p.height_m;
    const double tex_h = body / frac, tex_w = tex_h * aspect;
    Eigen::Vector3f o, right, down;
    if (p.posture == Posture::kLying) {
      const Eigen::Vector3f head(std::cos(p.yaw_rad), std::sin(p.yaw_rad), 0);
      right = Eigen::Vector3f(-head.y(), head.x(), 0);
      down = -head;  // image rows run from the head to the feet
      const Eigen::Vector3f head_top = Eigen::Vector3f(p.position.x(), p.position.y(), 0.26f) + head * 0.9f;
      o = head_top - head * static_cast<float>(-top_frac * tex_h) - right * static_cast<float>(tex_w / 2);
      o = head_top + head * static_cast<float>(top_frac * tex_h) - right * static_cast<float>(tex_w / 2);
    } else {
      Eigen::Vector2f to_cam = cam_pos.head<2>() - p.position.cast<float>();
      if (to_cam.norm() < 1e-3f) to_cam = Eigen::Vector2f(1, 0);
      to_cam.normalize();
      right = Eigen::Vector3f(-to_cam.y(), to_cam.x(), 0);  // viewer's right: (f.y, -f.x), f = -to_cam
      down = Eigen::Vector3f(0, 0, -1);
      const float top_z = static_cast<float>(body + top_frac * tex_h);
      o = Eigen::Vector3f(p.position.x(), p.position.y(), top_z) - right * static_cast<float>(tex_w / 2);
    }
    const Eigen::Vector3f s_axis = right * static_cast<float>(tex_w), t_axis = down * static_cast<float>(tex_h);
    // Corners: top-left, top-right, bottom-right, bottom-left (any winding; two-sided).
    vertices_[4 * index] = o + t_axis;
    vertices_[4 * index + 1] = o + t_axis + s_axis;
    vertices_[4 * index + 2] = o + s_axis;
    vertices_[4 * index + 3] = o;
    poly.normal = s_axis.cross(-t_axis).normalized();
    poly.tex_origin = cam_R_map * (o - cam_pos);
    poly.tex_s = cam_R_map * right / static_cast<float>(tex_w);
    poly.tex_t = cam_R_map * down / static_cast<float>(tex_h);
  }

  const double t0 = CpuSeconds();
  std::vector<Eigen::Vector3f> cam(vertices_.size());
  for (size_t k = 0; k < vertices_.size(); ++k) cam[k] = cam_R_map * (vertices_[k] - cam_pos);
  std::fill(ir_z_.begin(), ir_z_.end(), 0.0f);
  std::fill(color_z_.begin(), color_z_.end(), 0.0f);
  std::fill(ir_id_.begin(), ir_id_.end(), -1);
  std::fill(color_id_.begin(), color_id_.end(), -1);
  std::fill(glass_layers_.begin(), glass_layers_.end(), 0);
  std::vector<int> glass;
  for (size_t k = 0; k < polygons_.size(); ++k) {
    Polygon& poly = polygons_[k];
    poly.n_cam = cam_R_map * poly.normal;
    poly.d_cam = poly.n_cam.dot(cam[4 * k]);
    if (std::abs(poly.d_cam) < 1e-6f) continue;               // seen edge-on
    if (!(poly.flags & kTwoSided) && poly.d_cam > 0) continue;  // back face
    if (poly.flags & kGlass) {
      glass.push_back(static_cast<int>(k));
      continue;
    }
    Rasterise(poly, static_cast<int>(k), cam);
  }
  for (int k : glass) Rasterise(polygons_[k], k, cam);

  const float fx = static_cast<float>(intrinsics_.fx), fy = static_cast<float>(intrinsics_.fy);
  const float cx = static_cast<float>(intrinsics_.cx), cy = static_cast<float>(intrinsics_.cy);

  const double t1 = CpuSeconds();
  timing_.raster_s += t1 - t0;
  // Colour (deferred shading: one polygon lookup per pixel).
  out->rgb.resize(N * 3);
  const float gain = (lights_on_ ? 1.0f : static_cast<float>(options_.dark_gain)) * 255.0f;
  const int8_t* colour_noise = colour_noise_i8_.data() + XorShift(&rng_state_) % kNoiseSlack;
  const int8_t* depth_noise = noise_i8_.data() + XorShift(&rng_state_) % kNoiseSlack;
  const uint16_t* uniform = uniform_u16_.data() + XorShift(&rng_state_) % kNoiseSlack;
  std::vector<float> rx(W);
  for (int i = 0; i < W; ++i) rx[i] = (i - cx) / fx;
  const bool textured = appearances_ && !appearances_->empty();
  // Texture coordinates of a billboard pixel: with the pixel ray r = (rx, ry, 1) and depth z,
  // s = z (S . r) - S . O (and t likewise), S the scaled column axis and O the corner.
  // Bilinear filtering only where the photo is magnified (nearest is as good at ~1:1).
  struct Tex {
    Eigen::Vector3f s, t;
    float s0, t0;
    bool bilinear;
  };
  std::vector<Tex> tex(polygons_.size());
  for (size_t k = first_billboard_; k < polygons_.size(); ++k) {
    const Polygon& poly = polygons_[k];
    bool bilinear = true;
    if (textured) {
      const Appearance& app = (*appearances_)[poly.appearance];
      const float depth = std::max(0.1f, poly.tex_origin.z());  // the top corner's depth
      const float texel_m = 1.0f / (poly.tex_t.norm() * app.height);  // metres per texel (rows)
      bilinear = fy * texel_m / depth > 1.5f;                         // pixels per texel
    }
    tex[k] = {poly.tex_s, poly.tex_t, poly.tex_origin.dot(poly.tex_s), poly.tex_origin.dot(poly.tex_t), bilinear};
  }
  // Flat polygons: their final 8-bit colour, once per frame (the common, cheap case).
  std::vector<std::array<uint8_t, 3>> flat(polygons_.size());
  auto to_byte = [&](float v) { return static_cast<uint8_t>(std::min(255, std::max(0, static_cast<int>(v * gain + 0.5f)))); };
  for (size_t k = 0; k < polygons_.size(); ++k) {
    flat[k] = {to_byte(polygons_[k].shade[0]), to_byte(polygons_[k].shade[1]), to_byte(polygons_[k].shade[2])};
  }
  const std::array<uint8_t, 3> background = {to_byte(background_[0]), to_byte(background_[1]), to_byte(background_[2])};
  // Surface texture: the cube of the map point a pixel sees, hashed to a brightness factor.
  // map point = R z (rx, ry, 1) + t, with R, t of map_from_camera and z its depth. The cubes
  // are offset by odd fractions of a cell: walls and floors sit at round coordinates, and a
  // surface on a cube boundary would flicker between two cells.
  const float texture = static_cast<float>(options_.surface_texture);
  const Eigen::Matrix3f map_r = map_from_camera.rotation().toRotationMatrix().cast<float>();
  const Eigen::Vector3f map_t = map_from_camera.translation().cast<float>();
  const float inv_cell = static_cast<float>(1.0 / options_.surface_texture_cell_m);
  auto texture_factor = [&](float x, float y, float z) {
    x += 0.0371f, y += 0.0213f, z += 0.0297f;
    uint32_t h = static_cast<uint32_t>(static_cast<int32_t>(std::floor(x * inv_cell))) * 73856093u ^
                 static_cast<uint32_t>(static_cast<int32_t>(std::floor(y * inv_cell))) * 19349663u ^
                 static_cast<uint32_t>(static_cast<int32_t>(std::floor(z * inv_cell))) * 83492791u;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return 1.0f + texture * (static_cast<float>(h & 0xffff) * (2.0f / 65535.0f) - 1.0f);
  };
  for (int j = 0; j < H; ++j) {
    const float ry = (j - cy) / fy;
    for (int i = 0; i < W; ++i) {
      const size_t p = static_cast<size_t>(j) * W + i;
      const int id = color_id_[p];
      uint8_t* dst = &out->rgb[p * 3];
      const bool billboard = id >= 0 && (polygons_[id].flags & kBillboard) && textured;
      if (!billboard && glass_layers_[p] == 0) {
        const std::array<uint8_t, 3>& f = id >= 0 ? flat[id] : background;
        if (texture > 0 && id >= 0) {
          const float z = 1.0f / color_z_[p];
          const Eigen::Vector3f w = map_r * Eigen::Vector3f(z * rx[i], z * ry, z) + map_t;
          const float k = texture_factor(w.x(), w.y(), w.z());
          for (int ch = 0; ch < 3; ++ch)
            dst[ch] = static_cast<uint8_t>(std::min(255.0f, std::max(0.0f, f[ch] * k + 0.5f)));
          continue;
        }
        dst[0] = f[0];
        dst[1] = f[1];
        dst[2] = f[2];
        continue;
      }
      float c[3] = {background_[0], background_[1], background_[2]};  // nothing hit: sky or far dark
      if (id >= 0) {
        const Polygon& poly = polygons_[id];
        if ((poly.flags & kBillboard) && textured) {
          const Appearance& app = (*appearances_)[poly.appearance];
          const Tex& tx = tex[id];
          const float z = 1.0f / color_z_[p];
          const float su = z * (tx.s.x() * rx[i] + tx.s.y() * ry + tx.s.z()) - tx.s0;
          const float tv = z * (tx.t.x() * rx[i] + tx.t.y() * ry + tx.t.z()) - tx.t0;
          const float sf = std::min(std::max(su, 0.0f), 1.0f) * (app.width - 1);
          const float tf = std::min(std::max(tv, 0.0f), 1.0f) * (app.height - 1);
          if (!tx.bilinear) {
            const uint8_t* texel = &app.rgb[(static_cast<size_t>(tf + 0.5f) * app.width + static_cast<size_t>(sf + 0.5f)) * 3];
            c[0] = texel[0] * (1.0f / 255.0f);
            c[1] = texel[1] * (1.0f / 255.0f);
            c[2] = texel[2] * (1.0f / 255.0f);
          } else {
            const int s0 = std::min(static_cast<int>(sf), app.width - 2), t0 = std::min(static_cast<int>(tf), app.height - 2);
            const float fs = sf - s0, ft = tf - t0;
            const uint8_t* r0 = &app.rgb[(static_cast<size_t>(t0) * app.width + s0) * 3];
            const uint8_t* r1 = r0 + static_cast<size_t>(app.width) * 3;
            constexpr float kByte = 1.0f / 255.0f;
            const float w00 = (1 - ft) * (1 - fs) * kByte, w01 = (1 - ft) * fs * kByte, w10 = ft * (1 - fs) * kByte,
                        w11 = ft * fs * kByte;
            for (int ch = 0; ch < 3; ++ch) c[ch] = w00 * r0[ch] + w01 * r0[ch + 3] + w10 * r1[ch] + w11 * r1[ch + 3];
          }
        } else {
          c[0] = poly.shade[0];
          c[1] = poly.shade[1];
          c[2] = poly.shade[2];
        }
      }
      for (int g = 0; g < glass_layers_[p]; ++g) {  // each pane face: a faint blue-green tint
        c[0] = 0.84f * c[0] + 0.16f * 0.70f;
        c[1] = 0.84f * c[1] + 0.16f * 0.82f;
        c[2] = 0.84f * c[2] + 0.16f * 0.88f;
      }
      for (int ch = 0; ch < 3; ++ch) dst[ch] = to_byte(c[ch]);
    }
  }
  // Sensor noise, pre-scaled for the lighting, in one vectorisable saturating pass.
  {
    uint8_t* rgb = out->rgb.data();
    const int8_t* nz = colour_noise;
    for (size_t q = 0; q < 3 * N; ++q) {
      const int v = rgb[q] + nz[q];
      rgb[q] = static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }

  const double t2 = CpuSeconds();
  timing_.colour_s += t2 - t1;
  // Depth, and which people are in view (body pixels in the IR buffer). The noise is added
  // in disparity, where the Kinect makes it: d = b f / z + N(0, (k b f)^2) gives
  // sigma_z = z^2 sigma_d / (b f) = k z^2 to first order; the buffer already holds 1/z, so
  // the only division per pixel is the quantised disparity's back to depth.
  out->depth_mm.assign(N, 0);
  if (out->fill_true_depth) out->true_depth_m.assign(N, std::numeric_limits<float>::infinity());
  out->person_pixels.assign(people_.size(), 0);
  out->person_box.assign(people_.size(), {W, H, -1, -1});
  const float bf = static_cast<float>(options_.baseline_m * options_.depth_fx_px);
  const float sub = static_cast<float>(options_.disparity_subpixel);
  const float cos_limit = static_cast<float>(std::cos(options_.grazing_limit_deg * M_PI / 180.0));
  const float iz_min = static_cast<float>(1.0 / options_.max_range_m), iz_max = static_cast<float>(1.0 / options_.min_range_m);
  const float d_min = bf * iz_min, d_max = bf * iz_max;
  const float sigma_d32 = static_cast<float>(options_.depth_noise_k) * bf / 32.0f;  // noise int8 = N(0,1) * 32
  const int drop_threshold = static_cast<int>(std::lround(options_.dropout * 65536.0));
  for (int j = 0; j < H; ++j) {
    const float ry = (j - cy) / fy;
    for (int i = 0; i < W; ++i) {
      const size_t p = static_cast<size_t>(j) * W + i;
      const int id = ir_id_[p];
      if (id < 0) continue;
      const float iz = ir_z_[p];
      if (out->fill_true_depth) out->true_depth_m[p] = 1.0f / iz;
      const Polygon& poly = polygons_[id];
      if (poly.person >= 0) {
        ++out->person_pixels[poly.person];
        auto& b = out->person_box[poly.person];
        b[0] = std::min(b[0], i);
        b[1] = std::min(b[1], j);
        b[2] = std::max(b[2], i);
        b[3] = std::max(b[3], j);
      }
      if (!depth_fov_[p] || iz < iz_min || iz > iz_max) continue;
      const float ndotr = poly.n_cam.x() * rx[i] + poly.n_cam.y() * ry + poly.n_cam.z();
      if (std::abs(ndotr) * ray_inv_norm_[p] < cos_limit) continue;
      if (uniform[p] < drop_threshold) continue;
      float disparity = bf * iz + sigma_d32 * depth_noise[p];
      if (sub > 0) disparity = std::floor(disparity * sub + 0.5f) / sub;
      if (disparity < d_min || disparity > d_max) continue;
      out->depth_mm[p] = static_cast<uint16_t>(bf * 1000.0f / disparity + 0.5f);
    }
  }
  if (options_.shadows) {
    // The projector sits beside the camera: a background point is dark when a nearer
    // surface lies on its projector ray. In image rows: point x with disparity d(x) = b f/z is
    // lit iff x + d(x) exceeds x' + d(x') of every x' < x.
    const float bfc = static_cast<float>(options_.baseline_m * intrinsics_.fx);
    for (int j = 0; j < H; ++j) {
      float reach = -1e9f;
      for (int i = 0; i < W; ++i) {
        const size_t p = static_cast<size_t>(j) * W + i;
        if (ir_id_[p] < 0) continue;
        const float x = i + bfc * ir_z_[p];
        if (x < reach - 1.0f) out->depth_mm[p] = 0;
        reach = std::max(reach, x);
      }
    }
  }

  timing_.depth_s += CpuSeconds() - t2;
  ++timing_.frames;
}

}  // namespace sim
}  // namespace sarmap
