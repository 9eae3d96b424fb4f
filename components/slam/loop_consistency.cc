#include "slam/loop_consistency.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace sarmap {
namespace slam {

void ChainDrift::Add(const Rigid2d& local_pose) {
  if (size_ == 0) {
    last_ = {local_pose, Eigen::Matrix3d::Zero()};
    entries_[size_++] = last_;
    return;
  }
  const Rigid2d& prev = last_.pose;
  const double d_m = (local_pose.translation() - prev.translation()).norm();
  const double a_rad = std::abs(std::remainder(local_pose.yaw_rad() - prev.yaw_rad(), 2 * M_PI));
  const double q_t = model_.translation_m_per_sqrt_m * model_.translation_m_per_sqrt_m * d_m;
  const double q_r = model_.rotation_rad_per_sqrt_rad * model_.rotation_rad_per_sqrt_rad * a_rad +
                     model_.rotation_rad_per_sqrt_m * model_.rotation_rad_per_sqrt_m * d_m;
  // M = Ad Q Ad^T with Ad = [R, v; 0, 1], v = (y, -x); R q_t I R^T = q_t I.
  const Eigen::Vector2d v(local_pose.translation().y(), -local_pose.translation().x());
  Eigen::Matrix3d m;
  m.topLeftCorner<2, 2>() = q_t * Eigen::Matrix2d::Identity() + q_r * v * v.transpose();
  m.topRightCorner<2, 1>() = q_r * v;
  m.bottomLeftCorner<1, 2>() = q_r * v.transpose();
  m(2, 2) = q_r;
  last_ = {local_pose, Eigen::Matrix3d(last_.prefix + m)};
  entries_[size_++] = last_;
}

Eigen::Matrix3d ChainDrift::RelativeCovariance(int a, int b) const {
  const auto ia = entries_.find(a), ib = entries_.find(b);
  if (ia == entries_.end() || ib == entries_.end()) return Eigen::Matrix3d::Constant(INFINITY);
  const Eigen::Matrix3d& pa = ia->second.prefix;
  const Eigen::Matrix3d& pb = ib->second.prefix;
  const Eigen::Matrix3d s = a < b ? Eigen::Matrix3d(pb - pa) : Eigen::Matrix3d(pa - pb);
  const Eigen::Vector2d& t = ib->second.pose.translation();
  Eigen::Matrix3d lever = Eigen::Matrix3d::Identity();
  lever(0, 2) = -t.y();
  lever(1, 2) = t.x();
  return lever * s * lever.transpose();
}

double LoopClosureMahalanobisSquared(const Rigid2d& predicted, const Rigid2d& measured,
                                     const Eigen::Matrix3d& covariance) {
  Eigen::Vector3d e;
  e.head<2>() = measured.translation() - predicted.translation();
  e(2) = std::remainder(measured.yaw_rad() - predicted.yaw_rad(), 2 * M_PI);
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(covariance);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return INFINITY;
  const double d2 = e.dot(ldlt.solve(e));
  return std::isfinite(d2) ? d2 : INFINITY;
}

bool LoopClosureConsistent(const ChainDrift& chain, int reference, int node,
                           const Rigid2d& predicted, const Rigid2d& measured, double match_sigma_m,
                           double match_sigma_rad, double max_chi2, double* d2) {
  Eigen::Matrix3d covariance = chain.RelativeCovariance(reference, node);
  const Eigen::Vector3d match_variance(match_sigma_m * match_sigma_m, match_sigma_m * match_sigma_m,
                                       match_sigma_rad * match_sigma_rad);
  covariance += 2 * match_variance.asDiagonal().toDenseMatrix();
  const double distance2 = LoopClosureMahalanobisSquared(predicted, measured, covariance);
  if (d2) *d2 = distance2;
  return distance2 <= max_chi2;
}

}  // namespace slam
}  // namespace sarmap
