#pragma once
// Shared geometry of the sound map: planar robot poses, where the microphone array sits on
// the robot, and the inverse-depth (IDP) bearing observation model (Su 2017, eqs. 4.3-4.4).
// Everything is templated on the scalar so the same code gives EKF Jacobians (ceres::Jet)
// and Ceres residuals.

#include <Eigen/Core>
#include <cmath>

#include "common/angles.h"
#include "common/transform.h"

namespace sarmap {
namespace sound_map {

// A planar pose map_from_base: position (x, y) in metres, yaw in radians, as the estimators'
// state (the EKF's vector, Ceres' parameter blocks); what enters and leaves the map is a
// common::Rigid2d.
struct Pose2 {
  double x = 0, y = 0, yaw = 0;
  Pose2() = default;
  Pose2(double x_m, double y_m, double yaw_rad) : x(x_m), y(y_m), yaw(yaw_rad) {}
  Eigen::Vector3d vec() const { return Eigen::Vector3d(x, y, yaw); }
  static Pose2 FromVec(const Eigen::Vector3d& v) { return Pose2(v[0], v[1], v[2]); }
};

using common::WrapAngle;  // doubles and Ceres jets

// The estimators' planar pose of a map_from_base transform (the interfaces take Rigid2d),
// and back (yaw wrapped to (-pi, pi]).
inline Pose2 ToPose2(const common::Rigid2d& pose) {
  return Pose2(pose.translation().x(), pose.translation().y(), pose.yaw_rad());
}
inline common::Rigid2d ToRigid2d(const Pose2& pose) {
  return common::Rigid2d(pose.x, pose.y, pose.yaw);
}

// a ∘ b for planar poses.
inline Pose2 Compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  return Pose2(a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, WrapAngle(a.yaw + b.yaw));
}
// a^-1 ∘ b: b seen from a.
inline Pose2 Between(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return Pose2(c * dx + s * dy, -s * dx + c * dy, WrapAngle(b.yaw - a.yaw));
}

// The array frame on a planar robot: translation (x, y, z) and yaw of mic_array in base.
// (Roll/pitch of a 2D/3D array on a ground robot are taken as zero here.)
struct ArrayMount {
  double x_m = 0, y_m = 0, z_m = 0, yaw_rad = 0;
};

// Array origin in the map for robot pose (px, py, pyaw).
template <class T>
void ArrayOrigin(const T* pose, const ArrayMount& mount, T* origin_xy) {
  using std::cos;
  using std::sin;
  origin_xy[0] = pose[0] + cos(pose[2]) * T(mount.x_m) - sin(pose[2]) * T(mount.y_m);
  origin_xy[1] = pose[1] + sin(pose[2]) * T(mount.x_m) + cos(pose[2]) * T(mount.y_m);
}

// Inverse-depth source anchored at the array origin of robot pose `anchor`:
//   p = o(anchor) + m(theta, phi) / rho,   m = (cos phi cos theta, cos phi sin theta, sin phi)
// with theta, phi the map-frame azimuth/elevation of the ray (2D: phi = 0, no z).
// Observed from robot pose `current` (array origin c, array yaw = yaw + mount yaw):
//   d = rho (o - c) + m       (the ray scaled by rho: finite even as rho -> 0)
//   azimuth   = atan2(d_y, d_x) - yaw_array
//   elevation = atan2(d_z, |d_xy|)            (3D only; o and c are at the same height)
// idp = (theta, rho) in 2D or (theta, phi, rho) in 3D; out: 1 or 2 angles.
template <class T>
void IdpObservation(const T* current, const T* anchor, const T* idp, bool three_d,
                    const ArrayMount& mount, T* out) {
  using std::atan2;
  using std::cos;
  using std::sin;
  using std::sqrt;
  T o[2], c[2];
  ArrayOrigin(anchor, mount, o);
  ArrayOrigin(current, mount, c);
  const T theta = idp[0];
  const T phi = three_d ? idp[1] : T(0.0);
  const T rho = three_d ? idp[2] : idp[1];
  const T dx = rho * (o[0] - c[0]) + cos(phi) * cos(theta);
  const T dy = rho * (o[1] - c[1]) + cos(phi) * sin(theta);
  const T dz = sin(phi);
  out[0] = WrapAngle(T(atan2(dy, dx)) - current[2] - T(mount.yaw_rad));
  if (three_d) out[1] = atan2(dz, sqrt(dx * dx + dy * dy));
}

// Euclidean map position of an IDP source (z relative to the map floor: mount height added).
template <class T>
void IdpToPoint(const T* anchor, const T* idp, bool three_d, const ArrayMount& mount, T* p) {
  using std::cos;
  using std::sin;
  T o[2];
  ArrayOrigin(anchor, mount, o);
  const T theta = idp[0];
  const T phi = three_d ? idp[1] : T(0.0);
  const T rho = three_d ? idp[2] : idp[1];
  p[0] = o[0] + cos(phi) * cos(theta) / rho;
  p[1] = o[1] + cos(phi) * sin(theta) / rho;
  p[2] = T(mount.z_m) + sin(phi) / rho;
}

// Bearing(s) of a Euclidean point p (x, y[, z]) from robot pose `pose` (for the joint
// optimisation). out: azimuth [, elevation] in the array frame.
template <class T>
void PointObservation(const T* pose, const T* p, bool three_d, const ArrayMount& mount, T* out) {
  using std::atan2;
  using std::sqrt;
  T c[2];
  ArrayOrigin(pose, mount, c);
  const T dx = p[0] - c[0], dy = p[1] - c[1];
  out[0] = WrapAngle(T(atan2(dy, dx)) - pose[2] - T(mount.yaw_rad));
  if (three_d) out[1] = atan2(p[2] - T(mount.z_m), sqrt(dx * dx + dy * dy));
}

// Range and bearing of a 2D landmark from a robot pose (exteroceptive sensor at the base).
template <class T>
void RangeBearing(const T* pose, const T* landmark, T* out) {
  using std::atan2;
  using std::sqrt;
  const T dx = landmark[0] - pose[0], dy = landmark[1] - pose[1];
  out[0] = sqrt(dx * dx + dy * dy);
  out[1] = WrapAngle(T(atan2(dy, dx)) - pose[2]);
}

}  // namespace sound_map
}  // namespace sarmap
