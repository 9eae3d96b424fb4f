#pragma once
// Ceres pieces shared by the ch. 5 linear-array mappers (the §5.5.1 simulation's Mapper in
// linear_array.cc and the online LinearArraySoundMap): 6-DoF keyframe poses, relative-pose
// (odometry) residuals and the linear array's angle residual. Internal to sound_map.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "common/angles.h"

namespace sarmap {
namespace sound_map {
namespace linear_costs {

using common::WrapAngle;  // doubles and Ceres jets

// A keyframe pose world_from_sensor as Ceres parameter blocks (quaternion x y z w, translation).
struct Pose6 {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Isometry3d iso() const {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = q.toRotationMatrix();
    m.translation() = t;
    return m;
  }
  static Pose6 From(const Eigen::Isometry3d& m) {
    Pose6 p;
    p.q = Eigen::Quaterniond(m.linear()).normalized();
    p.t = m.translation();
    return p;
  }
};

// Relative pose i -> j measured as (q_m, t_m):
//   e = [ (R_i'(t_j - t_i) - t_m) / s_t ; 2 vec(q_m^-1 q_i^-1 q_j) / s_r ]
struct Odometry6Cost {
  Eigen::Quaterniond qm;
  Eigen::Vector3d tm;
  double inv_st, inv_sr;
  template <class T>
  bool operator()(const T* qi_, const T* ti_, const T* qj_, const T* tj_, T* r) const {
    Eigen::Map<const Eigen::Quaternion<T>> qi(qi_), qj(qj_);
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> ti(ti_), tj(tj_);
    const Eigen::Quaternion<T> qij = qi.conjugate() * qj;
    const Eigen::Matrix<T, 3, 1> tij = qi.conjugate() * (tj - ti);
    const Eigen::Quaternion<T> dq = qm.cast<T>().conjugate() * qij;
    for (int k = 0; k < 3; ++k) {
      r[k] = (tij[k] - T(tm[k])) * T(inv_st);
      r[3 + k] = T(2.0) * dq.vec()[k] * T(inv_sr);
    }
    return true;
  }
};

// beta of source p seen from the keyframe (q, t): l = R'(p - t), beta = atan2(l_y, |l_xz|)
// (the array along the sensor's y axis; 5.1-5.2).
template <class T>
T BetaFromKeyframe(const T* q_, const T* t_, const T* p_) {
  using std::atan2;
  using std::sqrt;
  Eigen::Map<const Eigen::Quaternion<T>> q(q_);
  Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_), p(p_);
  const Eigen::Matrix<T, 3, 1> l = q.conjugate() * (p - t);
  return atan2(l[1], sqrt(l[0] * l[0] + l[2] * l[2]));
}

// (5.30-5.32): beta of the source in the keyframe minus the corrected observation.
struct BetaCost {
  double beta, inv_sigma;
  template <class T>
  bool operator()(const T* q, const T* t, const T* p, T* r) const {
    r[0] = (BetaFromKeyframe(q, t, p) - T(beta)) * T(inv_sigma);
    return true;
  }
};

// The same for an observation taken at keyframe_from_sensor = (R_o, t_o) off its keyframe
// (a DOA heard between keyframes):
//   l = R_o'(R'(p - t) - t_o),  e = (atan2(l_y, |l_xz|) - beta) / sigma
struct OffsetBetaCost {
  Eigen::Matrix3d r_o;
  Eigen::Vector3d t_o;
  double beta, inv_sigma;
  template <class T>
  bool operator()(const T* q_, const T* t_, const T* p_, T* r) const {
    using std::atan2;
    using std::sqrt;
    Eigen::Map<const Eigen::Quaternion<T>> q(q_);
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_), p(p_);
    const Eigen::Matrix<T, 3, 1> k = q.conjugate() * (p - t);
    const Eigen::Matrix<T, 3, 1> l = r_o.transpose().cast<T>() * (k - t_o.cast<T>());
    r[0] = (atan2(l[1], sqrt(l[0] * l[0] + l[2] * l[2])) - T(beta)) * T(inv_sigma);
    return true;
  }
};

}  // namespace linear_costs
}  // namespace sound_map
}  // namespace sarmap
