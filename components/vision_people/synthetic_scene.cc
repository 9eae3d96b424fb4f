#include "vision_people/synthetic_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace sarmap {
namespace vision_people {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Primitives in the world frame; each returns the ray parameter of the first hit (or inf).
struct Box {  // oriented about z: centre, half sizes (along its own x, y, z), yaw
  Eigen::Vector3d centre, half;
  double yaw;
};
struct Cylinder {  // vertical
  double x, y, r, z0, z1;
};
struct Sphere {
  Eigen::Vector3d c;
  double r;
};

double Hit(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  auto local = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector3d(c * v.x() + s * v.y(), -s * v.x() + c * v.y(), v.z());
  };
  const Eigen::Vector3d lo = local(o - b.centre), ld = local(d);
  double t0 = -kInf, t1 = kInf;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(ld(i)) < 1e-12) {
      if (std::abs(lo(i)) > b.half(i)) return kInf;
      continue;
    }
    double a = (-b.half(i) - lo(i)) / ld(i), e = (b.half(i) - lo(i)) / ld(i);
    if (a > e) std::swap(a, e);
    t0 = std::max(t0, a);
    t1 = std::min(t1, e);
  }
  return t0 <= t1 && t0 > 0 ? t0 : kInf;
}

double Hit(const Cylinder& cy, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const double ox = o.x() - cy.x, oy = o.y() - cy.y;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a < 1e-12) return kInf;
  const double b = 2 * (ox * d.x() + oy * d.y());
  const double c = ox * ox + oy * oy - cy.r * cy.r;
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return kInf;
  const double t = (-b - std::sqrt(disc)) / (2 * a);
  if (t <= 0) return kInf;
  const double z = o.z() + t * d.z();
  if (z >= cy.z0 && z <= cy.z1) return t;
  // Top cap.
  if (std::abs(d.z()) > 1e-12) {
    const double tc = (cy.z1 - o.z()) / d.z();
    const Eigen::Vector3d p = o + tc * d;
    if (tc > 0 && (p.x() - cy.x) * (p.x() - cy.x) + (p.y() - cy.y) * (p.y() - cy.y) <= cy.r * cy.r)
      return tc;
  }
  return kInf;
}

double Hit(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d oc = o - s.c;
  const double b = oc.dot(d), c = oc.squaredNorm() - s.r * s.r, a = d.squaredNorm();
  const double disc = b * b - a * c;
  if (disc < 0) return kInf;
  const double t = (-b - std::sqrt(disc)) / a;
  return t > 0 ? t : kInf;
}

struct World {
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<Sphere> spheres;
};

void AddPerson(const SyntheticPerson& p, World* w) {
  const double H = p.height_m;
  const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
  // Body axes: forward (c, s), left (-s, c).
  auto at = [&](double fwd, double left) {
    return Eigen::Vector2d(p.x_m + c * fwd - s * left, p.y_m + s * fwd + c * left);
  };
  auto box = [&](double fwd, double left, double z0, double z1, double half_fwd, double half_left) {
    const Eigen::Vector2d q = at(fwd, left);
    w->boxes.push_back({Eigen::Vector3d(q.x(), q.y(), 0.5 * (z0 + z1)),
                        Eigen::Vector3d(half_fwd, half_left, 0.5 * (z1 - z0)), p.yaw_rad});
  };
  if (p.posture == SyntheticPerson::kLying) {
    // On the back, head along +forward: head, chest (the highest part), legs.
    const double head_c = 0.5 * H - 0.11, torso_len = 0.34 * H,
                 leg_len = 0.5 * H - 0.22 - torso_len + 0.5 * H;
    const Eigen::Vector2d head = at(head_c, 0);
    w->spheres.push_back({Eigen::Vector3d(head.x(), head.y(), 0.1), 0.1});
    box(0.5 * H - 0.22 - 0.5 * torso_len, 0, 0.0, 0.23, 0.5 * torso_len, 0.18);
    for (double side : {-1.0, 1.0}) {
      box(-0.5 * H + 0.5 * leg_len, side * 0.09, 0.0, 0.14, 0.5 * leg_len, 0.065);
      box(0.5 * H - 0.22 - 0.5 * torso_len, side * 0.22, 0.0, 0.1, 0.4 * torso_len, 0.04);  // arms
    }
    return;
  }
  if (p.posture == SyntheticPerson::kSitting) {
    // On a 0.45 m seat (not modelled), facing forward: shins, thighs, torso, head.
    const double seat = 0.45, torso_top = seat + 0.33 * H;
    for (double side : {-1.0, 1.0}) {
      const Eigen::Vector2d shin = at(0.42, side * 0.09);
      w->cylinders.push_back({shin.x(), shin.y(), 0.06, 0.0, seat});
      box(0.22, side * 0.09, seat, seat + 0.14, 0.22, 0.07);
      const Eigen::Vector2d arm = at(0.05, side * 0.225);
      w->cylinders.push_back({arm.x(), arm.y(), 0.045, seat + 0.05, torso_top - 0.03});
    }
    box(0, 0, seat, torso_top, 0.11, 0.18);
    w->cylinders.push_back({p.x_m, p.y_m, 0.05, torso_top, torso_top + 0.07});
    w->spheres.push_back({Eigen::Vector3d(p.x_m, p.y_m, torso_top + 0.18), 0.11});
    return;
  }
  const double leg_top = 0.47 * H, torso_top = 0.82 * H;
  for (double side : {-1.0, 1.0}) {
    const Eigen::Vector2d leg = at(0, side * 0.09);
    w->cylinders.push_back({leg.x(), leg.y(), 0.065, 0.0, leg_top});
    const Eigen::Vector2d arm = at(0, side * 0.225);
    if (side > 0 && p.arm_raised_m > 0) {
      w->cylinders.push_back({arm.x(), arm.y(), 0.045, torso_top - 0.03, H + p.arm_raised_m});
    } else {
      w->cylinders.push_back({arm.x(), arm.y(), 0.045, 0.45 * H, torso_top - 0.03});
    }
  }
  w->boxes.push_back({Eigen::Vector3d(p.x_m, p.y_m, 0.5 * (leg_top + torso_top)),
                      Eigen::Vector3d(0.11, 0.18, 0.5 * (torso_top - leg_top)), p.yaw_rad});
  w->cylinders.push_back({p.x_m, p.y_m, 0.05, torso_top, H - 0.2});
  w->spheres.push_back({Eigen::Vector3d(p.x_m, p.y_m, H - 0.11), 0.11});
}

void AddObject(const SyntheticObject& ob, World* w) {
  const double c = std::cos(ob.yaw_rad), s = std::sin(ob.yaw_rad);
  auto at = [&](double fwd, double left) {
    return Eigen::Vector2d(ob.x_m + c * fwd - s * left, ob.y_m + s * fwd + c * left);
  };
  switch (ob.kind) {
    case SyntheticObject::kChair: {
      w->boxes.push_back(
          {Eigen::Vector3d(ob.x_m, ob.y_m, 0.45), Eigen::Vector3d(0.22, 0.22, 0.025), ob.yaw_rad});
      for (double f : {-0.19, 0.19}) {
        for (double l : {-0.19, 0.19}) {
          const Eigen::Vector2d leg = at(f, l);
          w->cylinders.push_back({leg.x(), leg.y(), 0.02, 0.0, 0.45});
        }
      }
      // The back from the seat (0.5 m) to 0.94 m; with height_m, an office chair's: the back
      // to 0.2 m below height_m and a headrest 0.24 m wide above it.
      const Eigen::Vector2d back = at(0.2, 0);
      const double back_top = ob.height_m > 0 ? ob.height_m - 0.2 : 0.94;
      w->boxes.push_back({Eigen::Vector3d(back.x(), back.y(), 0.5 * (0.5 + back_top)),
                          Eigen::Vector3d(0.02, 0.22, 0.5 * (back_top - 0.5)), ob.yaw_rad});
      if (ob.height_m > 0) {
        w->boxes.push_back({Eigen::Vector3d(back.x(), back.y(), ob.height_m - 0.1),
                            Eigen::Vector3d(0.03, 0.12, 0.1), ob.yaw_rad});
      }
      break;
    }
    case SyntheticObject::kTable: {
      w->boxes.push_back(
          {Eigen::Vector3d(ob.x_m, ob.y_m, 0.73), Eigen::Vector3d(0.4, 0.6, 0.02), ob.yaw_rad});
      for (double f : {-0.36, 0.36}) {
        for (double l : {-0.56, 0.56}) {
          const Eigen::Vector2d leg = at(f, l);
          w->cylinders.push_back({leg.x(), leg.y(), 0.025, 0.0, 0.71});
        }
      }
      break;
    }
    case SyntheticObject::kCabinet: {
      const double h = ob.height_m > 0 ? ob.height_m : 1.9;
      w->boxes.push_back(
          {Eigen::Vector3d(ob.x_m, ob.y_m, h / 2), Eigen::Vector3d(0.25, 0.4, h / 2), ob.yaw_rad});
      break;
    }
    case SyntheticObject::kPole: {  // a coat stand: pole, base and a knob on top
      const double h = ob.height_m > 0 ? ob.height_m : 1.8;
      w->cylinders.push_back({ob.x_m, ob.y_m, 0.025, 0.0, h - 0.08});
      w->cylinders.push_back({ob.x_m, ob.y_m, 0.2, 0.0, 0.04});
      w->spheres.push_back({Eigen::Vector3d(ob.x_m, ob.y_m, h - 0.08), 0.08});
      break;
    }
    case SyntheticObject::kSlab: {  // a lying-body-sized crate or bag of debris
      const double h = ob.height_m > 0 ? ob.height_m : 0.25;
      w->boxes.push_back({Eigen::Vector3d(ob.x_m, ob.y_m, h / 2),
                          Eigen::Vector3d(0.85, 0.225, h / 2), ob.yaw_rad});
      break;
    }
    case SyntheticObject::kBox: {
      const double h = ob.height_m > 0 ? ob.height_m : 1.2;
      w->boxes.push_back(
          {Eigen::Vector3d(ob.x_m, ob.y_m, h / 2), Eigen::Vector3d(0.3, 0.3, h / 2), ob.yaw_rad});
      break;
    }
  }
}

}  // namespace

Eigen::Matrix3d SyntheticScene::world_R_camera() const {
  const double c = std::cos(camera_pitch_rad), s = std::sin(camera_pitch_rad);
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(0, -1, 0);  // camera x: right
  R.col(1) = Eigen::Vector3d(s, 0, -c);  // camera y: down
  R.col(2) = Eigen::Vector3d(c, 0, s);   // camera z: forward
  return R;
}

GroundPlane SyntheticScene::ground() const {
  return GroundFromMounting(world_R_camera(), world_t_camera());
}

namespace {
// Top of a person above the floor in its posture.
double PersonTop(const SyntheticPerson& p) {
  switch (p.posture) {
    case SyntheticPerson::kLying:
      return 0.23;
    case SyntheticPerson::kSitting:
      return 0.45 + 0.33 * p.height_m + 0.29;
    case SyntheticPerson::kStanding:
      break;
  }
  return p.height_m;
}
}  // namespace

Eigen::Vector3d SyntheticScene::PersonInCamera(const SyntheticPerson& p) const {
  return world_R_camera().transpose() *
         (Eigen::Vector3d(p.x_m, p.y_m, 0.5 * PersonTop(p)) - world_t_camera());
}

namespace {
// Ray casts `world` (plus floor and wall when `background`); metres along camera z, 0 = none.
std::vector<double> Cast(const SyntheticScene& sc, const World& world, bool background) {
  const Eigen::Matrix3d R = sc.world_R_camera();
  const Eigen::Vector3d o = sc.world_t_camera();
  std::vector<double> z(static_cast<size_t>(sc.width) * sc.height, 0.0);
  for (int v = 0; v < sc.height; ++v) {
    for (int u = 0; u < sc.width; ++u) {
      const Eigen::Vector3d ray_cam((u - sc.intrinsics.cx) / sc.intrinsics.fx,
                                    (v - sc.intrinsics.cy) / sc.intrinsics.fy, 1.0);
      const Eigen::Vector3d d = R * ray_cam;  // t along d is the camera z
      double t = kInf;
      if (background && d.z() < -1e-9) t = std::min(t, -o.z() / d.z());
      if (background && sc.back_wall_m > 0 && d.x() > 1e-9)
        t = std::min(t, (sc.back_wall_m - o.x()) / d.x());
      for (const auto& b : world.boxes) t = std::min(t, Hit(b, o, d));
      for (const auto& c : world.cylinders) t = std::min(t, Hit(c, o, d));
      for (const auto& s : world.spheres) t = std::min(t, Hit(s, o, d));
      if (std::isfinite(t)) z[static_cast<size_t>(v) * sc.width + u] = t;
    }
  }
  return z;
}
}  // namespace

std::vector<uint16_t> SyntheticScene::RenderDepth(uint32_t seed) const {
  World world;
  for (const auto& p : people) AddPerson(p, &world);
  for (const auto& o : objects) AddObject(o, &world);
  const std::vector<double> truth = Cast(*this, world, true);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<uint16_t> depth(truth.size(), 0);
  for (size_t i = 0; i < truth.size(); ++i) {
    double z = truth[i];
    if (z < min_range_m || z > max_range_m) continue;
    z += depth_noise_coeff * z * z * gauss(rng);
    depth[i] = static_cast<uint16_t>(std::clamp(std::lround(z * 1000.0), 1L, 65535L));
  }
  return depth;
}

double SyntheticScene::VisibleFraction(size_t index) const {
  const SyntheticPerson& p = people.at(index);
  // Head and feet must be in the image (15 px from its edges); lying: both ends of the body.
  const Eigen::Matrix3d Rt = world_R_camera().transpose();
  std::vector<Eigen::Vector3d> ends = {{p.x_m, p.y_m, 0.0}, {p.x_m, p.y_m, PersonTop(p)}};
  if (p.posture == SyntheticPerson::kLying) {
    const Eigen::Vector3d half(0.5 * p.height_m * std::cos(p.yaw_rad),
                               0.5 * p.height_m * std::sin(p.yaw_rad), 0.0);
    ends = {Eigen::Vector3d(p.x_m, p.y_m, 0.1) + half, Eigen::Vector3d(p.x_m, p.y_m, 0.1) - half};
  }
  for (const Eigen::Vector3d& end : ends) {
    const Eigen::Vector3d c = Rt * (end - world_t_camera());
    if (c.z() < min_range_m || c.z() > max_range_m) return 0.0;
    const double u = intrinsics.fx * c.x() / c.z() + intrinsics.cx;
    const double v = intrinsics.fy * c.y() / c.z() + intrinsics.cy;
    if (u < 15 || u > width - 16 || v < 15 || v > height - 16) return 0.0;  // with a margin
  }
  World alone, all;
  AddPerson(p, &alone);
  for (const auto& q : people) AddPerson(q, &all);
  for (const auto& o : objects) AddObject(o, &all);
  const std::vector<double> mine = Cast(*this, alone, false);
  const std::vector<double> full = Cast(*this, all, true);
  int64_t body = 0, seen = 0;
  for (size_t i = 0; i < mine.size(); ++i) {
    if (mine[i] <= 0) continue;
    ++body;
    seen += std::abs(full[i] - mine[i]) < 1e-6;
  }
  return body ? static_cast<double>(seen) / body : 0.0;
}

void RenderFrame(const SyntheticScene& scene, uint32_t seed, bool dark_color, RgbdFrame* frame) {
  const std::vector<uint16_t> depth = scene.RenderDepth(seed);
  CloudFromDepth(depth.data(), scene.width, scene.height, 0.001, scene.intrinsics, frame);
  frame->rgb.clear();
  if (dark_color) {
    std::mt19937 rng(seed + 1);
    std::uniform_int_distribution<int> noise(0, 6);
    frame->rgb.resize(static_cast<size_t>(scene.width) * scene.height * 3);
    for (auto& b : frame->rgb) b = static_cast<uint8_t>(noise(rng));
  }
}

}  // namespace vision_people
}  // namespace sarmap
