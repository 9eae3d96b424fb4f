#include "sound_map/online_sound_map.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <set>

namespace sarmap {
namespace sound_map {

namespace {
IdpEkf::Options EkfOptions(const OnlineSoundMapOptions& o, const ArrayMount& mount) {
  IdpEkf::Options e;
  e.three_d = o.three_d;
  e.mount = mount;
  e.initial_inverse_depth = 1.0 / o.initial_range_m;
  e.inverse_depth_sigma = o.inverse_depth_sigma;
  return e;
}
}  // namespace

OnlineSoundMap::OnlineSoundMap(const OnlineSoundMapOptions& options, const ArrayMount& mount)
    : options_(options),
      ekf_(EkfOptions(options, mount)),
      associator_(SourceAssociator::Options{options.gate_chi2, options.max_signature_distance}) {}

void OnlineSoundMap::OnPose(int64_t, const Pose2& pose, const Eigen::Matrix3d& cov, int64_t node_id) {
  if (!pose.vec().allFinite() || !cov.allFinite()) {
    ++counters_.bad_poses;
    return;
  }
  if (!have_pose_) {
    ekf_.Reset(pose, cov);
    have_pose_ = true;
  } else {
    // The current pose moves by the localisation map's increment; its uncertainty grows
    // with the motion until the next SLAM_ANCHORS resets it (with correlations).
    const Pose2 delta = Between(last_pose_, pose);
    const double dist = std::hypot(delta.x, delta.y);
    const double sp = options_.motion_noise_m_per_m * dist + 1e-4;
    const double sy = options_.motion_noise_rad_per_m * dist + options_.motion_noise_rad_per_rad * std::abs(delta.yaw) + 1e-5;
    ekf_.Predict(delta, Eigen::Vector3d(sp * sp, sp * sp, sy * sy).asDiagonal());
    ekf_.SetCurrentMean(pose);
  }
  last_pose_ = pose;
  last_node_id_ = node_id;
}

bool OnlineSoundMap::OnSlamAnchors(int64_t, const Pose2& current,
                                   const std::vector<std::pair<int64_t, Pose2>>& anchors,
                                   const Eigen::MatrixXd& covariance) {
  const int m = 3 * (1 + static_cast<int>(anchors.size()));
  bool ok = covariance.rows() == m && covariance.cols() == m && covariance.allFinite() &&
            current.vec().allFinite();
  std::set<int64_t> seen;
  for (const auto& a : anchors) ok = ok && a.second.vec().allFinite() && seen.insert(a.first).second;
  if (!ok) {  // wrong size, non-finite values or a node listed twice
    ++counters_.bad_anchors;
    return false;
  }
  if (!have_pose_) {
    ekf_.Reset(current, covariance.topLeftCorner<3, 3>());
    have_pose_ = true;
    last_pose_ = current;
    return true;
  }
  ekf_.BackPropagate(current, anchors, covariance);
  last_pose_ = current;
  ++counters_.back_propagations;
  return true;
}

void OnlineSoundMap::OnDoa(int64_t utime, const std::string& device, const std::vector<Doa>& doas) {
  for (const Doa& doa : doas) {
    if (doa.kind != kAzimuth && doa.kind != kAzimuthElevation) {
      ++counters_.doa_unsupported_kind;  // cone angles of linear arrays need the 6-DoF mapper
      continue;
    }
    if (!have_pose_) {
      ++counters_.doa_before_pose;
      continue;
    }
    const double floor = std::pow(options_.doa_sigma_floor_deg * M_PI / 180, 2);
    Eigen::VectorXd z(options_.three_d ? 2 : 1);
    Eigen::MatrixXd r = Eigen::MatrixXd::Zero(z.size(), z.size());
    z[0] = doa.azimuth_rad;
    r(0, 0) = std::max(doa.covariance(0, 0), floor);
    if (options_.three_d) {
      if (doa.kind == kAzimuthElevation) {
        z[1] = doa.elevation_rad;
        r(1, 1) = std::max(doa.covariance(1, 1), floor);
        r(0, 1) = r(1, 0) = doa.covariance(0, 1);
      } else {
        z[1] = 0.0;
        r(1, 1) = std::pow(options_.elevation_sigma_deg * M_PI / 180, 2);
      }
    }
    // Candidates for an unknown track: converged sources that have been quiet a while.
    std::vector<int64_t> ids;
    const bool may_reassociate = !doa.signature.empty() || options_.reassociate_without_signature;
    for (int64_t id : ekf_.source_ids()) {
      if (!may_reassociate) break;
      const Meta& m = meta_[id];
      if (utime - m.last >= static_cast<int64_t>(options_.reassociate_after_silence_s * 1e6) && Converged(id))
        ids.push_back(id);
    }
    const auto decision = associator_.Associate(device, doa.track_id, doa.signature, ids,
                                                [&](int64_t s) { return ekf_.SourceChi2(s, z, r); });
    int64_t source = decision.source;
    if (source < 0) {
      source = next_source_id_++;
      int64_t anchor = last_node_id_;
      if (anchor < 0) anchor = next_local_anchor_--;
      if (!ekf_.HasAnchor(anchor) && anchor >= 0) anchors_changed_ = true;
      ekf_.AddSource(source, anchor, z, r);
      meta_[source].first = utime;
      ++counters_.doa_new_sources;
    } else {
      const double chi2 = ekf_.UpdateSource(source, z, r, options_.update_gate_chi2);
      if (options_.update_gate_chi2 > 0 && chi2 > options_.update_gate_chi2) {
        ++counters_.doa_gated_out;
        continue;
      }
      counters_.doa_reassociated += decision.reassociated;
    }
    associator_.Commit(device, doa.track_id, source, doa.signature);
    Meta& meta = meta_[source];
    meta.last = utime;
    ++meta.n;
    ++counters_.doa_used;
  }
}

void OnlineSoundMap::OnHeardPerson(const std::string& device, int64_t track_id) {
  const int64_t s = associator_.SourceOfTrack(device, track_id);
  if (s >= 0) meta_[s].is_person = true;
}

std::vector<int64_t> OnlineSoundMap::AnchorNodeIds() const {
  std::set<int64_t> ids;
  for (int64_t s : ekf_.source_ids()) {
    const int64_t a = ekf_.source_anchor(s);
    if (a >= 0) ids.insert(a);
  }
  return std::vector<int64_t>(ids.begin(), ids.end());
}

bool OnlineSoundMap::TakeAnchorsChanged() {
  const bool c = anchors_changed_;
  anchors_changed_ = false;
  return c;
}

bool OnlineSoundMap::Converged(int64_t id) const {
  Eigen::Vector3d p;
  Eigen::Matrix3d c;
  ekf_.SourcePoint(id, &p, &c);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff())) < options_.converged_sigma_m;
}

std::vector<OnlineSoundMap::Source> OnlineSoundMap::Sources(int64_t now) const {
  std::vector<Source> out;
  for (int64_t id : ekf_.source_ids()) {
    Source s;
    s.id = id;
    ekf_.SourcePoint(id, &s.position_m, &s.covariance);
    const Meta& m = meta_.at(id);
    s.is_person = m.is_person;
    s.first_heard_utime = m.first;
    s.last_heard_utime = m.last;
    s.num_observations = m.n;
    s.state = Converged(id) ? Source::kConverged : Source::kInitialising;
    if (now - m.last > static_cast<int64_t>(options_.silent_after_s * 1e6)) s.state = Source::kSilent;
    out.push_back(s);
  }
  return out;
}

}  // namespace sound_map
}  // namespace sarmap
