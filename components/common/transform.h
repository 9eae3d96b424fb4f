#pragma once
// Rigid transforms named by the frames they connect: `map_from_base` maps points in the
// base frame to the map frame. Framed* variants carry the frame names and refuse to compose
// transforms whose frames do not chain (a -> b, b -> c), which catches the classic
// inverted-extrinsic bug at the first use instead of as a wrong map.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/angles.h"

namespace sarmap {
namespace common {

// A camera's body frame (x forward, y left, z up) from its optical frame (z forward, x right,
// y down, as OpenCV and PCL): the columns are the optical axes expressed in the body frame.
inline Eigen::Matrix3d BodyFromOpticalRotation() {
  Eigen::Matrix3d r;
  r << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  return r;
}


class Rigid2d {
 public:
  Rigid2d() = default;
  Rigid2d(const Eigen::Vector2d& translation, double yaw_rad)
      : translation_(translation), yaw_rad_(WrapAngle(yaw_rad)) {}
  Rigid2d(double x_m, double y_m, double yaw_rad) : Rigid2d(Eigen::Vector2d(x_m, y_m), yaw_rad) {}
  static Rigid2d Identity() { return Rigid2d(); }

  const Eigen::Vector2d& translation() const { return translation_; }
  double yaw_rad() const { return yaw_rad_; }
  Eigen::Rotation2Dd rotation() const { return Eigen::Rotation2Dd(yaw_rad_); }

  Rigid2d inverse() const {
    const Eigen::Rotation2Dd inv(-yaw_rad_);
    return Rigid2d(-(inv * translation_), -yaw_rad_);
  }
  Rigid2d operator*(const Rigid2d& rhs) const {
    return Rigid2d(translation_ + rotation() * rhs.translation_, yaw_rad_ + rhs.yaw_rad_);
  }
  Eigen::Vector2d operator*(const Eigen::Vector2d& point) const {
    return translation_ + rotation() * point;
  }

 private:
  Eigen::Vector2d translation_ = Eigen::Vector2d::Zero();
  double yaw_rad_ = 0.0;
};

// The pose a fraction f of the way from a to b: translation linear, yaw along the shorter arc.
inline Rigid2d Interpolate(const Rigid2d& a, const Rigid2d& b, double f) {
  return Rigid2d(a.translation() + f * (b.translation() - a.translation()),
                 a.yaw_rad() + f * WrapAngle(b.yaw_rad() - a.yaw_rad()));
}

class Rigid3d {
 public:
  Rigid3d() = default;
  Rigid3d(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation)
      : translation_(translation), rotation_(rotation.normalized()) {}
  static Rigid3d Identity() { return Rigid3d(); }
  // The planar pose lifted to 3D (z = 0, rotation about +z).
  static Rigid3d FromRigid2d(const Rigid2d& pose) {
    return Rigid3d(Eigen::Vector3d(pose.translation().x(), pose.translation().y(), 0.0),
                   Eigen::Quaterniond(Eigen::AngleAxisd(pose.yaw_rad(), Eigen::Vector3d::UnitZ())));
  }
  // Drops z, roll and pitch.
  Rigid2d ToRigid2d() const {
    const Eigen::Vector3d x_axis = rotation_ * Eigen::Vector3d::UnitX();
    return Rigid2d(translation_.head<2>(), std::atan2(x_axis.y(), x_axis.x()));
  }
  Eigen::Isometry3d ToIsometry() const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = rotation_.toRotationMatrix();
    t.translation() = translation_;
    return t;
  }

  const Eigen::Vector3d& translation() const { return translation_; }
  const Eigen::Quaterniond& rotation() const { return rotation_; }

  Rigid3d inverse() const {
    const Eigen::Quaterniond inv = rotation_.conjugate();
    return Rigid3d(-(inv * translation_), inv);
  }
  Rigid3d operator*(const Rigid3d& rhs) const {
    return Rigid3d(translation_ + rotation_ * rhs.translation_, rotation_ * rhs.rotation_);
  }
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return translation_ + rotation_ * point;
  }

 private:
  Eigen::Vector3d translation_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation_ = Eigen::Quaterniond::Identity();
};

class FrameMismatch : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// parent_from_child with its frame names.
template <class Rigid>
struct Framed {
  std::string parent;
  std::string child;
  Rigid transform;

  Framed inverse() const { return Framed{child, parent, transform.inverse()}; }
  // (a_from_b) * (b_from_c) = a_from_c; throws FrameMismatch unless the frames chain.
  Framed operator*(const Framed& rhs) const {
    if (child != rhs.parent) {
      throw FrameMismatch("cannot compose " + parent + "_from_" + child + " with " + rhs.parent +
                          "_from_" + rhs.child);
    }
    return Framed{parent, rhs.child, transform * rhs.transform};
  }
};
using FramedRigid2d = Framed<Rigid2d>;
using FramedRigid3d = Framed<Rigid3d>;

}  // namespace common
}  // namespace sarmap
