#pragma once
// Test helper: a synthetic RGB-D view of a textured room with boxes, rendered from a known
// pose (ray casting, exact depth, Lambertian 3D texture so a point looks the same from every
// view). Shared by the unit tests and the node's process test.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "rgbd_odometry/rgbd_odometry.h"

namespace sarmap {
namespace rgbd_odometry {
namespace synthetic {

// Synthetic scene: the inside of a room (x in [-3, 3], y in [-2.5, 2.5], z in [0, 2.8], world z
// up) with a few boxes, every surface painted with a smooth 3D texture (Lambertian, so a point
// has the same intensity from every view).

struct Box {
  Eigen::Vector3d lo, hi;
};

class Room {
 public:
  Room() {
    boxes_ = {{{1.5, -1.0, 0.0}, {2.2, -0.3, 0.9}},
              {{2.0, 0.5, 0.0}, {2.6, 1.4, 1.5}},
              {{1.0, 0.8, 0.0}, {1.3, 1.1, 2.8}},
              {{2.4, -1.9, 1.2}, {3.0, -1.2, 1.8}}};
  }

  static PinholeCamera Kinect() { return {525.0, 525.0, 319.5, 239.5}; }

  // A frame seen from world_from_optical (optical: z forward, x right, y down).
  RgbdFrame Render(const Eigen::Isometry3d& world_from_optical, int64_t utime,
                   double depth_unit_m = 0.001) const {
    const int w = 640, h = 480;
    const PinholeCamera cam = Kinect();
    RgbdFrame f;
    f.utime = utime;
    f.width = w;
    f.height = h;
    f.depth_unit_m = depth_unit_m;
    f.camera = cam;
    f.depth.assign(static_cast<size_t>(w) * h, 0);
    f.image.assign(static_cast<size_t>(w) * h, 0);
    f.image_channels = 1;
    const Eigen::Matrix3d r = world_from_optical.linear();
    const Eigen::Vector3d o = world_from_optical.translation();
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const Eigen::Vector3d d =
            r * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
        const double t = Cast(o, d);  // = depth, as the optical ray has z = 1
        if (!(t > 0 && t < 10)) continue;
        const size_t i = static_cast<size_t>(v) * w + u;
        f.depth[i] = static_cast<uint16_t>(std::lround(t / depth_unit_m));
        f.image[i] = Texture(o + t * d);
      }
    }
    return f;
  }

 private:
  // Ray parameter of the first surface hit from inside the room.
  double Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    const Eigen::Vector3d room_lo(-3, -2.5, 0), room_hi(3, 2.5, 2.8);
    double t = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-12) continue;
      const double bound = d[a] > 0 ? room_hi[a] : room_lo[a];
      t = std::min(t, (bound - o[a]) / d[a]);
    }
    for (const Box& b : boxes_) {
      double t0 = -std::numeric_limits<double>::infinity(),
             t1 = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (std::abs(d[a]) < 1e-12) {
          if (o[a] < b.lo[a] || o[a] > b.hi[a]) t0 = t1 + 1;
          continue;
        }
        double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t0 <= t1 && t0 > 0) t = std::min(t, t0);
    }
    return t;
  }

  static uint8_t Texture(const Eigen::Vector3d& p) {
    const double i = 128 + 45 * std::sin(2 * M_PI * (p.x() + 0.6 * p.y() + 0.3 * p.z()) / 0.21) +
                     35 * std::sin(2 * M_PI * (-0.4 * p.x() + p.y() + 0.8 * p.z()) / 0.13) +
                     30 * std::sin(2 * M_PI * (0.7 * p.x() - 0.5 * p.y() + p.z()) / 0.17 + 1.0);
    return static_cast<uint8_t>(std::clamp(i, 0.0, 255.0));
  }

  std::vector<Box> boxes_;
};

// The camera at the room's middle, 1.2 m up, looking along world +x (so the optical frame in
// the world is RigFromOptical() translated).
inline Eigen::Isometry3d StartPose() {
  Eigen::Isometry3d t = RigFromOptical();
  t.translation() = Eigen::Vector3d(0.0, 0.0, 1.2);
  return t;
}

// A motion in the world frame: translation then rotation about a world axis through the camera.
inline Eigen::Isometry3d Moved(const Eigen::Isometry3d& world_from_optical,
                               const Eigen::Vector3d& t, const Eigen::Vector3d& axis,
                               double angle_rad) {
  Eigen::Isometry3d out = world_from_optical;
  out.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix() *
                 world_from_optical.linear();
  out.translation() += t;
  return out;
}

}  // namespace synthetic
}  // namespace rgbd_odometry
}  // namespace sarmap
