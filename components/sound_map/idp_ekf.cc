#include "sound_map/idp_ekf.h"

#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <stdexcept>

namespace sarmap {
namespace sound_map {

namespace {
using Jet9 = ceres::Jet<double, 9>;
}

IdpEkf::IdpEkf(const Options& options) : options_(options) { Reset(Pose2(), Eigen::Matrix3d::Zero()); }

void IdpEkf::Reset(const Pose2& current, const Eigen::Matrix3d& covariance) {
  x_ = current.vec();
  p_ = covariance;
  is_angle_ = {0, 0, 1};
  anchors_.clear();
  landmarks_.clear();
  sources_.clear();
}

int IdpEkf::Append(int n, bool angle_first) {
  const int old = dim();
  x_.conservativeResize(old + n);
  x_.tail(n).setZero();
  Eigen::MatrixXd grown = Eigen::MatrixXd::Zero(old + n, old + n);
  grown.topLeftCorner(old, old) = p_;
  p_.swap(grown);
  for (int i = 0; i < n; ++i) is_angle_.push_back(0);
  if (angle_first) is_angle_[old] = 1;
  return old;
}

void IdpEkf::WrapAngles() {
  for (int i = 0; i < dim(); ++i)
    if (is_angle_[i]) x_[i] = WrapAngle(x_[i]);
}

void IdpEkf::Predict(const Pose2& u, const Eigen::Matrix3d& q) {
  const double c = std::cos(x_[2]), s = std::sin(x_[2]);
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  f(0, 2) = -s * u.x - c * u.y;
  f(1, 2) = c * u.x - s * u.y;
  Eigen::Matrix3d g = Eigen::Matrix3d::Identity();
  g.topLeftCorner<2, 2>() << c, -s, s, c;
  const Pose2 next = Compose(current(), u);
  x_.head<3>() = next.vec();
  const int n = dim();
  // Only the current pose moves: P_cc <- F P_cc F' + G Q G', P_c* <- F P_c*.
  if (n > 3) {
    p_.block(0, 3, 3, n - 3) = f * p_.block(0, 3, 3, n - 3);
    p_.block(3, 0, n - 3, 3) = p_.block(0, 3, 3, n - 3).transpose();
  }
  p_.topLeftCorner<3, 3>() = f * p_.topLeftCorner<3, 3>() * f.transpose() + g * q * g.transpose();
}

void IdpEkf::AddAnchor(int64_t id) {
  if (HasAnchor(id)) return;
  const int i = Append(3, false);
  is_angle_[i + 2] = 1;
  x_.segment<3>(i) = x_.head<3>();
  p_.block(i, 0, 3, i) = p_.block(0, 0, 3, i);
  p_.block(0, i, i, 3) = p_.block(0, 0, i, 3);
  p_.block<3, 3>(i, i) = p_.topLeftCorner<3, 3>();
  anchors_[id] = i;
}

Pose2 IdpEkf::anchor(int64_t id) const { return Pose2::FromVec(x_.segment<3>(anchors_.at(id))); }

void IdpEkf::AddLandmark(int64_t id, const Eigen::Vector2d& z, const Eigen::Matrix2d& r) {
  if (HasLandmark(id)) return;
  const double a = x_[2] + z[1];
  const double c = std::cos(a), s = std::sin(a);
  const int i = Append(2, false);
  x_[i] = x_[0] + z[0] * c;
  x_[i + 1] = x_[1] + z[0] * s;
  Eigen::Matrix<double, 2, 3> gx;
  gx << 1, 0, -z[0] * s, 0, 1, z[0] * c;
  Eigen::Matrix2d gz;
  gz << c, -z[0] * s, s, z[0] * c;
  const Eigen::MatrixXd p_c_all = p_.block(0, 0, 3, i);
  p_.block(i, 0, 2, i) = gx * p_c_all;
  p_.block(0, i, i, 2) = p_.block(i, 0, 2, i).transpose();
  p_.block<2, 2>(i, i) = gx * p_.topLeftCorner<3, 3>() * gx.transpose() + gz * r * gz.transpose();
  landmarks_[id] = i;
}

Eigen::Vector2d IdpEkf::landmark(int64_t id) const { return x_.segment<2>(landmarks_.at(id)); }
Eigen::Matrix2d IdpEkf::landmark_covariance(int64_t id) const {
  const int i = landmarks_.at(id);
  return p_.block<2, 2>(i, i);
}

double IdpEkf::UpdateLandmark(int64_t id, const Eigen::Vector2d& z, const Eigen::Matrix2d& r,
                              double gate) {
  const int i = landmarks_.at(id);
  using Jet5 = ceres::Jet<double, 5>;
  Jet5 pose[3], lm[2], out[2];
  for (int k = 0; k < 3; ++k) pose[k] = Jet5(x_[k], k);
  for (int k = 0; k < 2; ++k) lm[k] = Jet5(x_[i + k], 3 + k);
  RangeBearing(pose, lm, out);
  Eigen::MatrixXd h(2, 5);
  Eigen::VectorXd nu(2);
  for (int k = 0; k < 2; ++k) h.row(k) = out[k].v.transpose();
  nu[0] = z[0] - out[0].a;
  nu[1] = WrapAngle(z[1] - out[1].a);
  return Correct({0, 1, 2, i, i + 1}, h, nu, r, gate);
}

void IdpEkf::AddSource(int64_t id, int64_t anchor_id, const Eigen::VectorXd& z,
                       const Eigen::MatrixXd& r) {
  if (HasSource(id)) return;
  if (z.size() != obs_dim() || r.rows() != obs_dim() || r.cols() != obs_dim())
    throw std::invalid_argument("IdpEkf::AddSource: observation size does not match the map");
  if (!HasAnchor(anchor_id)) AddAnchor(anchor_id);
  const int a = anchors_.at(anchor_id);
  const int sd = source_dim();
  const int i = Append(sd, true);
  // Ray direction in the map: theta = anchor yaw + mount yaw + azimuth, phi = elevation.
  // The anchor is the pose the ray was heard from, so theta depends on the anchor's yaw.
  x_[i] = WrapAngle(x_[a + 2] + options_.mount.yaw_rad + z[0]);
  if (options_.three_d) x_[i + 1] = z[1];
  x_[i + sd - 1] = options_.initial_inverse_depth;
  Eigen::MatrixXd ga = Eigen::MatrixXd::Zero(sd, 3);  // d source / d anchor pose
  ga(0, 2) = 1.0;
  Eigen::MatrixXd gz = Eigen::MatrixXd::Zero(sd, obs_dim());
  gz(0, 0) = 1.0;
  if (options_.three_d) gz(1, 1) = 1.0;
  const Eigen::MatrixXd cross = ga * p_.block(a, 0, 3, i);
  p_.block(i, 0, sd, i) = cross;
  p_.block(0, i, i, sd) = cross.transpose();
  Eigen::MatrixXd pss = ga * p_.block(a, a, 3, 3) * ga.transpose() + gz * r * gz.transpose();
  pss(sd - 1, sd - 1) += options_.inverse_depth_sigma * options_.inverse_depth_sigma;
  if (options_.three_d) pss(1, 1) += std::pow(options_.initial_elevation_sigma_rad, 2);
  p_.block(i, i, sd, sd) = pss;
  sources_[id] = Source{i, anchor_id};
}

void IdpEkf::RemoveBlock(int i, int sd) {
  const int n = dim();
  std::vector<int> keep;
  for (int k = 0; k < n; ++k)
    if (k < i || k >= i + sd) keep.push_back(k);
  Eigen::VectorXd x = x_(keep);
  Eigen::MatrixXd p = p_(keep, keep);
  std::vector<char> ang;
  for (int k : keep) ang.push_back(is_angle_[k]);
  x_.swap(x);
  p_.swap(p);
  is_angle_.swap(ang);
  auto shift = [&](int& index) {
    if (index > i) index -= sd;
  };
  for (auto& kv : anchors_) shift(kv.second);
  for (auto& kv : landmarks_) shift(kv.second);
  for (auto& kv : sources_) shift(kv.second.index);
}

void IdpEkf::RemoveSource(int64_t id) {
  auto it = sources_.find(id);
  if (it == sources_.end()) return;
  const int i = it->second.index;
  sources_.erase(it);
  RemoveBlock(i, source_dim());
}

void IdpEkf::RemoveAnchor(int64_t id) {
  auto it = anchors_.find(id);
  if (it == anchors_.end()) return;
  for (const auto& kv : sources_)
    if (kv.second.anchor == id) return;
  const int i = it->second;
  anchors_.erase(it);
  RemoveBlock(i, 3);
}

Eigen::VectorXd IdpEkf::SourceInnovation(int64_t id, const Eigen::VectorXd& z, Eigen::MatrixXd* h,
                                         std::vector<int>* cols) const {
  const Source& s = sources_.at(id);
  const int a = anchors_.at(s.anchor);
  const int sd = source_dim(), m = obs_dim();
  Jet9 cur[3], anc[3], idp[3], out[2];
  for (int k = 0; k < 3; ++k) cur[k] = Jet9(x_[k], k);
  for (int k = 0; k < 3; ++k) anc[k] = Jet9(x_[a + k], 3 + k);
  for (int k = 0; k < sd; ++k) idp[k] = Jet9(x_[s.index + k], 6 + k);
  IdpObservation(cur, anc, idp, options_.three_d, options_.mount, out);
  Eigen::VectorXd nu(m);
  h->resize(m, 6 + sd);
  for (int k = 0; k < m; ++k) {
    nu[k] = z[k] - out[k].a;
    h->row(k) = out[k].v.head(6 + sd).transpose();
  }
  nu[0] = WrapAngle(nu[0]);
  *cols = {0, 1, 2, a, a + 1, a + 2};
  for (int k = 0; k < sd; ++k) cols->push_back(s.index + k);
  return nu;
}

double IdpEkf::SourceChi2(int64_t id, const Eigen::VectorXd& z, const Eigen::MatrixXd& r) const {
  Eigen::MatrixXd h;
  std::vector<int> cols;
  const Eigen::VectorXd nu = SourceInnovation(id, z, &h, &cols);
  const Eigen::MatrixXd s = h * p_(cols, cols) * h.transpose() + r;
  return nu.dot(s.ldlt().solve(nu));
}

double IdpEkf::UpdateSource(int64_t id, const Eigen::VectorXd& z, const Eigen::MatrixXd& r,
                            double gate) {
  if (z.size() != obs_dim()) throw std::invalid_argument("IdpEkf::UpdateSource: wrong size");
  Eigen::MatrixXd h;
  std::vector<int> cols;
  const Eigen::VectorXd nu = SourceInnovation(id, z, &h, &cols);
  return Correct(cols, h, nu, r, gate, !options_.source_updates_move_poses);
}

double IdpEkf::Correct(const std::vector<int>& cols, const Eigen::MatrixXd& h,
                       const Eigen::VectorXd& nu, const Eigen::MatrixXd& r, double gate, bool fix_poses) {
  // K = P H' (H P H' + R)^-1, x += K nu, P -= K S K'  (eqs. 4.8-4.10), with H non-zero
  // only on `cols`: P H' = P(:, cols) H'.
  const Eigen::MatrixXd pht = p_(Eigen::all, cols) * h.transpose();
  const Eigen::MatrixXd s = h * pht(cols, Eigen::all) + r;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(s);
  const double chi2 = nu.dot(ldlt.solve(nu));
  if (gate > 0 && chi2 > gate) return chi2;
  Eigen::MatrixXd k = ldlt.solve(pht.transpose()).transpose();
  if (fix_poses) {
    // Schmidt-Kalman: no gain on the pose states; P+ = P - K HP - (K HP)' + K S K'.
    k.topRows<3>().setZero();
    for (const auto& kv : anchors_) k.middleRows<3>(kv.second).setZero();
    x_ += k * nu;
    const Eigen::MatrixXd khp = k * pht.transpose();
    p_ -= khp + khp.transpose();
    p_.noalias() += k * s * k.transpose();
    WrapAngles();
    return chi2;
  }
  x_ += k * nu;
  // P -= K S K' written as K (P H')' keeps P symmetric up to rounding; it is re-symmetrised
  // at every back-propagation.
  p_.noalias() -= k * pht.transpose();
  WrapAngles();
  return chi2;
}

void IdpEkf::BackPropagate(const Pose2& current, const std::vector<std::pair<int64_t, Pose2>>& anchors,
                           const Eigen::MatrixXd& covariance, bool keep_covariance) {
  const int m = 3 * (1 + static_cast<int>(anchors.size()));
  if (covariance.rows() != m || covariance.cols() != m)
    throw std::invalid_argument("IdpEkf::BackPropagate: covariance must be 3(1+n) square");
  // x_C = the anchors this map holds; the message also carries the current pose.
  std::vector<int> a_idx, a_rows, cur_rows = {0, 1, 2};
  Eigen::VectorXd xb(m);
  xb.head<3>() = current.vec();
  for (size_t k = 0; k < anchors.size(); ++k) {
    xb.segment<3>(3 * (1 + k)) = anchors[k].second.vec();
    auto it = anchors_.find(anchors[k].first);
    if (it == anchors_.end()) continue;  // an anchor this map does not hold
    for (int j = 0; j < 3; ++j) {
      a_idx.push_back(it->second + j);
      a_rows.push_back(3 * (1 + static_cast<int>(k)) + j);
    }
  }
  std::vector<char> in_c(dim(), 0);
  in_c[0] = in_c[1] = in_c[2] = 1;
  for (int i : a_idx) in_c[i] = 1;
  std::vector<int> s_idx;
  for (int i = 0; i < dim(); ++i)
    if (!in_c[i]) s_idx.push_back(i);
  std::vector<int> c_idx = {0, 1, 2}, c_rows = cur_rows;
  c_idx.insert(c_idx.end(), a_idx.begin(), a_idx.end());
  c_rows.insert(c_rows.end(), a_rows.begin(), a_rows.end());
  const Eigen::MatrixXd p_cb = covariance(c_rows, c_rows);
  if (!s_idx.empty() && !a_idx.empty()) {
    // The sound map's own current pose is superseded (the localisation map has moved on):
    // it is marginalised, and x_S is regressed on the shared anchors only.
    Eigen::VectorXd dx = xb(a_rows) - x_(a_idx);
    for (size_t k = 0; k < a_idx.size(); ++k)
      if (is_angle_[a_idx[k]]) dx[k] = WrapAngle(dx[k]);
    const Eigen::MatrixXd p_a = p_(a_idx, a_idx);
    const Eigen::MatrixXd p_sa = p_(s_idx, a_idx);
    const Eigen::MatrixXd p_ab = covariance(a_rows, a_rows);
    // K12 = P_SC P_C^-1 (4.22); a tiny ridge keeps nearly identical anchors well posed.
    Eigen::MatrixXd p_a_reg = p_a;
    p_a_reg.diagonal().array() += 1e-12 + 1e-9 * p_a.diagonal().cwiseAbs().maxCoeff();
    const Eigen::MatrixXd k12 = p_a_reg.ldlt().solve(p_sa.transpose()).transpose();
    const Eigen::MatrixXd p_s = p_(s_idx, s_idx) + k12 * (p_ab - p_a) * k12.transpose();  // (4.24)
    const Eigen::MatrixXd p_scb = k12 * covariance(a_rows, c_rows);                        // (4.23)
    if (options_.back_propagate_sources) {
      x_(s_idx) = x_(s_idx) + k12 * dx;  // (4.25)
    } else {
      // Rigidly with the anchors: the ray's origin follows its anchor's array position, and its
      // azimuth (a map-frame angle) turns with the anchor's heading.
      for (auto& [id, src] : sources_) {
        auto it = anchors_.find(src.anchor);
        if (it == anchors_.end()) continue;
        for (size_t k = 0; k < a_idx.size(); k += 3) {
          if (a_idx[k] != it->second) continue;
          x_[src.index] += WrapAngle(dx[k + 2]);
        }
      }
    }
    if (keep_covariance) {
      x_(c_idx) = xb(c_rows);
      WrapAngles();
      return;
    }
    p_(s_idx, s_idx) = 0.5 * (p_s + p_s.transpose());
    p_(s_idx, c_idx) = p_scb;
    p_(c_idx, s_idx) = p_scb.transpose();
  } else if (keep_covariance) {
    x_(c_idx) = xb(c_rows);
    WrapAngles();
    return;
  } else if (!s_idx.empty()) {
    p_(s_idx, c_idx).setZero();
    p_(c_idx, s_idx).setZero();
  }
  x_(c_idx) = xb(c_rows);   // (4.20)
  p_(c_idx, c_idx) = p_cb;  // (4.21)
  WrapAngles();
}

void IdpEkf::SharedState(const std::vector<int64_t>& ids, Pose2* current,
                         std::vector<std::pair<int64_t, Pose2>>* anchors,
                         Eigen::MatrixXd* covariance) const {
  std::vector<int> idx = {0, 1, 2};
  anchors->clear();
  for (int64_t id : ids) {
    const int a = anchors_.at(id);
    for (int j = 0; j < 3; ++j) idx.push_back(a + j);
    anchors->emplace_back(id, anchor(id));
  }
  *current = this->current();
  *covariance = p_(idx, idx);
}

void IdpEkf::SourcePoint(int64_t id, Eigen::Vector3d* point, Eigen::Matrix3d* covariance) const {
  const Source& s = sources_.at(id);
  const int a = anchors_.at(s.anchor);
  const int sd = source_dim();
  using Jet6 = ceres::Jet<double, 6>;
  Jet6 anc[3], idp[3], p[3];
  for (int k = 0; k < 3; ++k) anc[k] = Jet6(x_[a + k], k);
  for (int k = 0; k < sd; ++k) idp[k] = Jet6(x_[s.index + k], 3 + k);
  if (idp[sd - 1].a < 1e-3) idp[sd - 1].a = 1e-3;
  IdpToPoint(anc, idp, options_.three_d, options_.mount, p);
  Eigen::Matrix<double, 3, Eigen::Dynamic> j(3, 3 + sd);
  for (int k = 0; k < 3; ++k) {
    (*point)[k] = p[k].a;
    j.row(k) = p[k].v.head(3 + sd).transpose();
  }
  std::vector<int> cols = {a, a + 1, a + 2};
  for (int k = 0; k < sd; ++k) cols.push_back(s.index + k);
  *covariance = j * p_(cols, cols) * j.transpose();
  if (!options_.three_d) (*covariance)(2, 2) = 0;
}

std::vector<int64_t> IdpEkf::source_ids() const {
  std::vector<int64_t> ids;
  for (const auto& kv : sources_) ids.push_back(kv.first);
  return ids;
}
std::vector<int64_t> IdpEkf::anchor_ids() const {
  std::vector<int64_t> ids;
  for (const auto& kv : anchors_) ids.push_back(kv.first);
  return ids;
}

void IdpEkf::Save(common::BinaryWriter* w) const {
  w->Matrix(x_);
  w->Matrix(p_);
  for (char a : is_angle_) w->Pod<int8_t>(a);
  auto blocks = [w](const std::map<int64_t, int>& m) {
    w->Pod<int64_t>(static_cast<int64_t>(m.size()));
    for (const auto& [id, index] : m) w->Pod<int64_t>(id), w->Pod<int32_t>(index);
  };
  blocks(anchors_);
  blocks(landmarks_);
  w->Pod<int64_t>(static_cast<int64_t>(sources_.size()));
  for (const auto& [id, s] : sources_)
    w->Pod<int64_t>(id), w->Pod<int32_t>(s.index), w->Pod<int64_t>(s.anchor);
}

void IdpEkf::Load(common::BinaryReader* r) {
  const Eigen::MatrixXd x = r->Matrix(), p = r->Matrix();
  const int n = static_cast<int>(x.rows());
  if (x.cols() != 1 || n < 3 || p.rows() != n || p.cols() != n) r->Corrupt("EKF dimensions");
  std::vector<char> is_angle(static_cast<size_t>(n));
  for (char& a : is_angle) a = r->Pod<int8_t>();
  auto blocks = [r, n](int size, std::map<int64_t, int>* m) {
    m->clear();
    const int64_t count = r->Count(n);
    for (int64_t k = 0; k < count; ++k) {
      const int64_t id = r->Pod<int64_t>();
      const int index = r->Pod<int32_t>();
      if (index < 3 || index + size > n) r->Corrupt("EKF block index");
      (*m)[id] = index;
    }
  };
  std::map<int64_t, int> anchors, landmarks;
  blocks(3, &anchors);
  blocks(2, &landmarks);
  std::map<int64_t, Source> sources;
  const int64_t count = r->Count(n);
  for (int64_t k = 0; k < count; ++k) {
    const int64_t id = r->Pod<int64_t>();
    Source s;
    s.index = r->Pod<int32_t>();
    s.anchor = r->Pod<int64_t>();
    if (s.index < 3 || s.index + source_dim() > n) r->Corrupt("EKF source index");
    if (!anchors.count(s.anchor)) r->Corrupt("EKF source without its anchor");
    sources[id] = s;
  }
  if (!x.allFinite() || !p.allFinite()) r->Corrupt("EKF state not finite");
  x_ = x.col(0);
  p_ = p;
  is_angle_ = std::move(is_angle);
  anchors_ = std::move(anchors);
  landmarks_ = std::move(landmarks);
  sources_ = std::move(sources);
}

}  // namespace sound_map
}  // namespace sarmap
