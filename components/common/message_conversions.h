#pragma once
// Between message fields and the geometry types of transform.h.

#include <Eigen/Core>

#include "common/transform.h"
#include "sarmap/odometry_t.hpp"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace common {

inline Rigid3d ToRigid3d(const double (&position_m)[3], const double (&orientation_wxyz)[4]) {
  return Rigid3d(Eigen::Vector3d(position_m[0], position_m[1], position_m[2]),
                 Eigen::Quaterniond(orientation_wxyz[0], orientation_wxyz[1], orientation_wxyz[2],
                                    orientation_wxyz[3]));
}

inline void FromRigid3d(const Rigid3d& pose, double (&position_m)[3], double (&orientation_wxyz)[4]) {
  for (int i = 0; i < 3; ++i) position_m[i] = pose.translation()[i];
  orientation_wxyz[0] = pose.rotation().w();
  orientation_wxyz[1] = pose.rotation().x();
  orientation_wxyz[2] = pose.rotation().y();
  orientation_wxyz[3] = pose.rotation().z();
}

// 3x3 row-major (x y z) covariance <-> Eigen.
inline Eigen::Matrix3d ToCovariance3(const double (&cov)[9]) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(cov);
}
inline void FromCovariance3(const Eigen::Matrix3d& m, double (&cov)[9]) {
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> out(cov);
  out = m;
}

// 6x6 row-major (x y z roll pitch yaw) covariance <-> Eigen.
inline Eigen::Matrix<double, 6, 6> ToCovariance6(const double (&cov)[36]) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(cov);
}
inline void FromCovariance6(const Eigen::Matrix<double, 6, 6>& m, double (&cov)[36]) {
  Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> out(cov);
  out = m;
}

// The planar (x, y, yaw) block of a 6x6 covariance, and back (other entries zero).
inline Eigen::Matrix3d PlanarCovariance(const Eigen::Matrix<double, 6, 6>& full) {
  const int idx[3] = {0, 1, 5};
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = full(idx[r], idx[c]);
  return out;
}
inline Eigen::Matrix3d PlanarCovariance(const double (&cov)[36]) {
  return PlanarCovariance(ToCovariance6(cov));
}
inline void SetPlanarCovariance(const Eigen::Matrix3d& planar, double (&cov)[36]) {
  Eigen::Matrix<double, 6, 6> full = Eigen::Matrix<double, 6, 6>::Zero();
  const int idx[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) full(idx[r], idx[c]) = planar(r, c);
  FromCovariance6(full, cov);
}

}  // namespace common
}  // namespace sarmap
