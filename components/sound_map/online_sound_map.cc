#include "sound_map/online_sound_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>

#include "common/state_file.h"

namespace sarmap {
namespace sound_map {

namespace {
IdpEkf::Options EkfOptions(const OnlineSoundMapOptions& o, const ArrayMount& mount) {
  IdpEkf::Options e;
  e.three_d = o.three_d;
  e.mount = mount;
  e.initial_inverse_depth = 1.0 / o.initial_range_m;
  e.inverse_depth_sigma = o.inverse_depth_sigma;
  e.source_updates_move_poses = o.doa_moves_poses;
  e.back_propagate_sources = o.back_propagate_sources;
  return e;
}
}  // namespace

OnlineSoundMap::OnlineSoundMap(const OnlineSoundMapOptions& options, const ArrayMount& mount)
    : options_(options),
      ekf_(EkfOptions(options, mount)),
      associator_(SourceAssociator::Options{options.gate_chi2, options.max_signature_distance}),
      evidence_(options.evidence, mount) {}

void OnlineSoundMap::OnPose(int64_t utime, const common::Rigid2d& map_from_base,
                            const Eigen::Matrix3d& cov, int64_t node_id) {
  const Pose2 pose = ToPose2(map_from_base);
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
    const double sy = options_.motion_noise_rad_per_m * dist +
                      options_.motion_noise_rad_per_rad * std::abs(delta.yaw) + 1e-5;
    ekf_.Predict(delta, Eigen::Vector3d(sp * sp, sp * sp, sy * sy).asDiagonal());
    ekf_.SetCurrentMean(pose);
    const double dt = (utime - last_pose_utime_) * 1e-6;
    if (dt > 1e-3) yaw_rate_rad_per_s_ = delta.yaw / dt;
  }
  last_pose_utime_ = utime;
  last_pose_ = pose;
  last_node_id_ = node_id;
  // The first POSE naming a node is the scan that made it: its pose is the node's pose.
  if (node_id >= 0 && !node_poses_.count(node_id)) node_poses_[node_id] = pose;
  AddToTrail(Eigen::Vector2d(pose.x, pose.y));
  Prune(utime);
}

void OnlineSoundMap::AddToTrail(const Eigen::Vector2d& p) {
  if (options_.path_clearance_m <= 0) return;
  if (!((last_trail_point_ - p).norm() < trail_step_m_)) {  // NaN at the start: add
    const double cell = options_.path_clearance_m;
    trail_cells_[TrailCell(static_cast<int64_t>(std::floor(p.x() / cell)),
                           static_cast<int64_t>(std::floor(p.y() / cell)))]
        .push_back(p);
    last_trail_point_ = p;
  }
}

bool OnlineSoundMap::OnTrail(const Eigen::Vector2d& p) const {
  if (!p.allFinite()) return false;
  const double cell = options_.path_clearance_m;
  const int64_t ix = static_cast<int64_t>(std::floor(p.x() / cell));
  const int64_t iy = static_cast<int64_t>(std::floor(p.y() / cell));
  for (int64_t dx = -1; dx <= 1; ++dx) {
    for (int64_t dy = -1; dy <= 1; ++dy) {
      auto it = trail_cells_.find(TrailCell(ix + dx, iy + dy));
      if (it == trail_cells_.end()) continue;
      for (const Eigen::Vector2d& q : it->second)
        if ((q - p).norm() < cell) return true;
    }
  }
  return false;
}

namespace {
// d(node o offset) / d(node) for a fixed offset.
Eigen::Matrix3d ComposeJacobian(const Pose2& node, const Pose2& offset) {
  const double c = std::cos(node.yaw), s = std::sin(node.yaw);
  Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
  j(0, 2) = -s * offset.x - c * offset.y;
  j(1, 2) = c * offset.x - s * offset.y;
  return j;
}
}  // namespace

bool OnlineSoundMap::OnSlamAnchors(
    int64_t, const common::Rigid2d& current_pose,
    const std::vector<std::pair<int64_t, common::Rigid2d>>& anchor_poses,
    const Eigen::MatrixXd& covariance, bool loop_closed) {
  const Pose2 current = ToPose2(current_pose);
  std::vector<std::pair<int64_t, Pose2>> anchors;
  anchors.reserve(anchor_poses.size());
  for (const auto& [id, pose] : anchor_poses) anchors.emplace_back(id, ToPose2(pose));
  const int m = 3 * (1 + static_cast<int>(anchors.size()));
  bool ok = covariance.rows() == m && covariance.cols() == m && covariance.allFinite() &&
            current.vec().allFinite();
  std::set<int64_t> seen;
  for (const auto& a : anchors)
    ok = ok && a.second.vec().allFinite() && seen.insert(a.first).second;
  if (!ok) {  // wrong size, non-finite values or a node listed twice
    ++counters_.bad_anchors;
    return false;
  }
  if (options_.anchors_after_loop_closure_only && !loop_closed && have_pose_) {
    ++counters_.anchors_skipped;
    return true;
  }
  // SLAM_ANCHORS' current is the latest node (the scan of the optimisation), not necessarily
  // the robot's latest POSE: carry it to the latest POSE by the offset between them.
  Pose2 node_from_current;
  auto np = node_poses_.find(last_node_id_);
  if (have_pose_ && np != node_poses_.end()) node_from_current = Between(np->second, last_pose_);
  const Pose2 now = Compose(current, node_from_current);
  if (!have_pose_) {
    ekf_.Reset(now, covariance.topLeftCorner<3, 3>());
    have_pose_ = true;
    last_pose_ = now;
  } else {
    // The shared state of this map: the current pose and every EKF anchor whose node is in
    // the message, each = node o node_from_anchor; its covariance J C J'.
    std::map<int64_t, int> node_index;
    for (size_t k = 0; k < anchors.size(); ++k) node_index[anchors[k].first] = static_cast<int>(k);
    std::vector<std::pair<int64_t, Pose2>> mine;
    std::vector<std::pair<int, Eigen::Matrix3d>> rows;  // message block, Jacobian
    rows.emplace_back(0, ComposeJacobian(current, node_from_current));
    for (const auto& [id, link] : anchor_links_) {
      auto it = node_index.find(link.node);
      if (it == node_index.end() || !ekf_.HasAnchor(id)) continue;
      const Pose2& node = anchors[it->second].second;
      mine.emplace_back(id, Compose(node, link.node_from_anchor));
      rows.emplace_back(1 + it->second, ComposeJacobian(node, link.node_from_anchor));
    }
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(3 * static_cast<int>(rows.size()), m);
    for (size_t r = 0; r < rows.size(); ++r)
      j.block<3, 3>(3 * r, 3 * rows[r].first) = rows[r].second;
    Eigen::MatrixXd cov = j * covariance * j.transpose();
    const double fp = options_.anchor_sigma_floor_m,
                 fy = options_.anchor_sigma_floor_deg * M_PI / 180;
    for (int i = 0; i < cov.rows(); i += 3) {
      cov(i, i) += fp * fp;
      cov(i + 1, i + 1) += fp * fp;
      cov(i + 2, i + 2) += fy * fy;
    }
    // use_slam_covariance false: means only (x_S += K12 dx), P stays this map's.
    ekf_.BackPropagate(now, mine, 0.5 * (cov + cov.transpose()), !options_.use_slam_covariance);
    last_pose_ = now;
    ++counters_.back_propagations;
  }
  for (const auto& a : anchors) node_poses_[a.first] = a.second;
  // The message's current is the latest node's new estimate.
  if (last_node_id_ >= 0) node_poses_[last_node_id_] = current;
  return true;
}

int64_t OnlineSoundMap::AnchorForBirth() {
  if (last_node_id_ < 0) return next_local_anchor_--;  // no SLAM node: a local anchor
  Pose2 node_from_anchor;
  auto np = node_poses_.find(last_node_id_);
  if (np != node_poses_.end()) node_from_anchor = Between(np->second, ekf_.current());
  // Sources born from the same pose share its anchor.
  for (const auto& [id, link] : anchor_links_) {
    if (link.node != last_node_id_ || !ekf_.HasAnchor(id)) continue;
    const Pose2 d = Between(link.node_from_anchor, node_from_anchor);
    if (std::hypot(d.x, d.y) < 1e-3 && std::abs(WrapAngle(d.yaw)) < 1e-3) return id;
  }
  const auto before = AnchorNodeIds();
  const int64_t id = next_anchor_id_++;
  anchor_links_[id] = AnchorLink{last_node_id_, node_from_anchor};
  if (std::find(before.begin(), before.end(), last_node_id_) == before.end())
    anchors_changed_ = true;
  return id;
}

bool OnlineSoundMap::MakeObs(const Doa& doa, Obs* obs) const {
  const double floor = std::pow(options_.doa_sigma_floor_deg * M_PI / 180, 2);
  const int d = options_.three_d ? 2 : 1;
  obs->z = Eigen::VectorXd::Zero(d);
  obs->r = Eigen::MatrixXd::Zero(d, d);
  obs->z[0] = doa.azimuth_rad;
  obs->r(0, 0) = std::max(doa.covariance(0, 0), floor);
  obs->mirrored = false;
  if (doa.kind == kAngle1d) {
    // Angle to the array axis (mic_array x), 0..pi: in the plane the bearing is +angle or
    // -angle (the cone meets the horizontal plane twice). Only the planar map takes it.
    if (options_.three_d) return false;
    obs->mirrored = true;
    return true;
  }
  if (doa.kind != kAzimuth && doa.kind != kAzimuthElevation) return false;
  if (options_.three_d) {
    if (doa.kind == kAzimuthElevation) {
      obs->z[1] = doa.elevation_rad;
      obs->r(1, 1) = std::max(doa.covariance(1, 1), floor);
      obs->r(0, 1) = obs->r(1, 0) = doa.covariance(0, 1);
    } else {
      obs->z[1] = 0.0;
      obs->r(1, 1) = std::pow(options_.elevation_sigma_deg * M_PI / 180, 2);
    }
  }
  return true;
}

double OnlineSoundMap::Chi2(int64_t source, const Obs& obs, Eigen::VectorXd* z_used) const {
  double best = ekf_.SourceChi2(source, obs.z, obs.r);
  if (z_used) *z_used = obs.z;
  if (obs.mirrored) {
    Eigen::VectorXd m = obs.z;
    m[0] = -m[0];
    const double c = ekf_.SourceChi2(source, m, obs.r);
    if (c < best) {
      best = c;
      if (z_used) *z_used = m;
    }
  }
  return std::isfinite(best) ? best : std::numeric_limits<double>::infinity();
}

void OnlineSoundMap::OnDoa(int64_t utime, const std::string& device, const std::vector<Doa>& doas) {
  std::set<int64_t> used;  // one DOA of a block per source
  const double update_gate = options_.update_gate_chi2 > 0
                                 ? options_.update_gate_chi2
                                 : std::numeric_limits<double>::infinity();
  for (const Doa& doa : doas) {
    Obs obs;
    if (!MakeObs(doa, &obs)) {
      ++counters_.doa_unsupported_kind;
      continue;
    }
    if (doa.kind == kAzimuthElevation && options_.max_abs_elevation_deg > 0 &&
        !(std::abs(doa.elevation_rad) <= options_.max_abs_elevation_deg * M_PI / 180)) {
      ++counters_.doa_too_steep;
      continue;
    }
    if (!have_pose_) {
      ++counters_.doa_before_pose;
      continue;
    }
    AddRay(utime, doa, false);
    if (options_.max_turn_rate_deg_per_s > 0 &&
        std::abs(yaw_rate_rad_per_s_) > options_.max_turn_rate_deg_per_s * M_PI / 180) {
      ++counters_.doa_while_turning;
      continue;
    }
    if (obs.mirrored) ++counters_.doa_angle_1d;
    // 1. The DOA track's source, a hint only: kept while its bearing stays consistent.
    int64_t source = -1;
    bool by_track = false;
    Eigen::VectorXd z;
    const int64_t hinted = doa.track_id >= 0 ? associator_.SourceOfTrack(device, doa.track_id) : -1;
    if (hinted >= 0 && ekf_.HasSource(hinted) && !used.count(hinted) &&
        Chi2(hinted, obs, &z) <= update_gate) {
      source = hinted;
      by_track = true;
    }
    // 2. Chi-square gate on the predicted bearing of every source (and the spectral signature
    //    when both carry one); the best one takes the DOA.
    if (source < 0) {
      std::vector<int64_t> ids;
      for (int64_t id : ekf_.source_ids())
        if (!used.count(id)) ids.push_back(id);
      const auto decision = associator_.Associate(device, -1, doa.signature, ids,
                                                  [&](int64_t s) { return Chi2(s, obs, nullptr); });
      source = decision.source;
      if (source >= 0) {
        Chi2(source, obs, &z);
        if (doa.track_id >= 0 && hinted >= 0 && hinted != source) ++counters_.doa_reassociated;
      }
    }
    // 3. Nothing fits: a tentative source (born after a few consistent DOAs).
    if (source < 0) {
      Tentate(utime, device, doa, obs);
      continue;
    }
    const double chi2 = ekf_.UpdateSource(source, z, obs.r, options_.update_gate_chi2);
    if (options_.update_gate_chi2 > 0 && chi2 > options_.update_gate_chi2) {
      ++counters_.doa_gated_out;
      continue;
    }
    (void)by_track;
    used.insert(source);
    associator_.Commit(device, doa.track_id, source, doa.signature);
    Meta& meta = meta_[source];
    if (doa.sound_class > 0 && doa.sound_class < 5) meta.class_votes[doa.sound_class] += 1;
    meta.last = utime;
    ++meta.n;
    meta.mirror_misses = 0;
    ++counters_.doa_used;
    // Linear arrays: the mirror twin is updated too while it explains the DOA; a twin that
    // keeps missing what this source explains was the ghost side of the cone.
    const int64_t twin = meta.twin;
    if (twin >= 0 && ekf_.HasSource(twin)) {
      Eigen::VectorXd zt;
      if (Chi2(twin, obs, &zt) <= options_.gate_chi2) {
        ekf_.UpdateSource(twin, zt, obs.r, options_.update_gate_chi2);
        Meta& tm = meta_[twin];
        tm.last = utime;
        ++tm.n;
        tm.mirror_misses = 0;
        used.insert(twin);
      } else if (++meta_[twin].mirror_misses >= options_.mirror_prune_misses) {
        Remove(twin);
        ++counters_.mirrors_pruned;
      }
    }
  }
  Prune(utime);
  if (options_.evidence.enabled &&
      utime - last_solve_utime_ >= static_cast<int64_t>(options_.evidence.solve_period_s * 1e6))
    SolveEvidence(utime);
}

void OnlineSoundMap::AddRay(int64_t utime, const Doa& doa, bool heard) {
  // Planar bearings only: a linear array's cone has two.
  if (!options_.evidence.enabled || (doa.kind != kAzimuth && doa.kind != kAzimuthElevation)) return;
  BearingEvidence::Ray ray;
  ray.utime = utime;
  ray.node = -1;
  ray.node_from_base = last_pose_;
  auto np = node_poses_.find(last_node_id_);
  if (last_node_id_ >= 0 && np != node_poses_.end()) {
    ray.node = last_node_id_;
    ray.node_from_base = Between(np->second, last_pose_);
  }
  // While turning, a DOA is heard with the array's heading of turn_lag_s earlier: the bearing
  // is turned back by the yaw rate times the lag, and its std grows by half that (the lag varies).
  const double lag_rad = options_.evidence.turn_lag_s * yaw_rate_rad_per_s_;
  ray.azimuth_rad = WrapAngle(doa.azimuth_rad - lag_rad);
  ray.sigma_rad = std::sqrt(std::max(doa.covariance(0, 0), 0.0) + 0.25 * lag_rad * lag_rad);
  ray.sound_class = doa.sound_class;
  ray.heard = heard;
  ray.called = doa.called;
  evidence_.Add(ray);
}

void OnlineSoundMap::SolveEvidence(int64_t utime) {
  last_solve_utime_ = utime;
  ++counters_.evidence_solves;
  const Eigen::Vector2d margin = Eigen::Vector2d::Constant(options_.site_margin_m);
  const Eigen::Vector2d lo = site_min_ - margin, hi = site_max_ + margin;
  auto sources =
      evidence_.Solve(node_poses_, have_site_ ? &lo : nullptr, have_site_ ? &hi : nullptr);
  // Ids: a source keeps the id of the nearest previous source within two peak radii.
  std::vector<int64_t> ids(sources.size(), -1);
  std::vector<bool> taken(evidence_sources_.size(), false);
  for (size_t k = 0; k < sources.size(); ++k) {
    double best = 2 * options_.evidence.peak_radius_m;
    int j_best = -1;
    for (size_t j = 0; j < evidence_sources_.size(); ++j) {
      const double d = (evidence_sources_[j].position_m - sources[k].position_m).norm();
      if (!taken[j] && d < best) best = d, j_best = static_cast<int>(j);
    }
    if (j_best >= 0) {
      taken[j_best] = true;
      ids[k] = evidence_ids_[j_best];
    } else {
      ids[k] = next_evidence_id_++;
    }
  }
  evidence_sources_ = std::move(sources);
  evidence_ids_ = std::move(ids);
}

void OnlineSoundMap::Tentate(int64_t utime, const std::string& device, const Doa& doa,
                             const Obs& obs) {
  ++counters_.doa_tentative;
  const int64_t window = static_cast<int64_t>(options_.birth_window_s * 1e6);
  for (auto it = tentatives_.begin(); it != tentatives_.end();) {
    if (utime - it->second.last > window) {
      ++counters_.tentatives_expired;
      it = tentatives_.erase(it);
    } else {
      ++it;
    }
  }
  // Map-frame bearing of the DOA (and of its mirror).
  const double base = last_pose_.yaw + ekf_.options().mount.yaw_rad;
  const double bearing = WrapAngle(base + obs.z[0]);
  const double mirror = WrapAngle(base - obs.z[0]);
  const double var = obs.r(0, 0);
  const double drift = options_.birth_drift_deg_per_s * M_PI / 180;
  int64_t best_key = -1;
  bool best_mirror = false;
  double best = options_.birth_gate_chi2;
  for (auto& kv : tentatives_) {
    const Tentative& t = kv.second;
    const double dt = (utime - t.last) * 1e-6;
    const double s = var + t.variance + std::pow(drift * dt, 2);
    for (int m = 0; m < (obs.mirrored ? 2 : 1); ++m) {
      const double d = WrapAngle((m ? mirror : bearing) - t.bearing_map_rad);
      double c = d * d / s;
      if (doa.track_id >= 0 && t.track_id == doa.track_id && t.device == device)
        c *= 0.5;  // the hint
      if (c <= best) {
        best = c;
        best_key = kv.first;
        best_mirror = m == 1;
      }
    }
  }
  if (best_key < 0) {
    Tentative t;
    t.first = t.last = utime;
    t.bearing_map_rad = bearing;
    t.variance = var;
    t.n = 1;
    t.track_id = doa.track_id;
    t.device = device;
    const int64_t key = next_tentative_++;
    // A cone angle near the axis has a single bearing; otherwise the mirror is a twin.
    if (obs.mirrored && std::sin(obs.z[0]) > 2 * std::sqrt(var)) {
      Tentative tw = t;
      tw.bearing_map_rad = mirror;
      const int64_t tkey = next_tentative_++;
      t.twin = tkey;
      tw.twin = key;
      tentatives_[tkey] = tw;
    }
    tentatives_[key] = t;
    best_key = key;
  } else {
    Tentative& t = tentatives_[best_key];
    t.last = utime;
    t.bearing_map_rad = best_mirror ? mirror : bearing;
    t.variance = var;
    ++t.n;
    if (doa.track_id >= 0) {
      t.track_id = doa.track_id;
      t.device = device;
    }
    auto tw = tentatives_.find(t.twin);
    if (tw != tentatives_.end()) {
      tw->second.last = utime;
      tw->second.bearing_map_rad = best_mirror ? bearing : mirror;
      tw->second.variance = var;
      tw->second.n = t.n;
    }
  }
  const Tentative& t = tentatives_.at(best_key);
  if (t.n >= options_.birth_min_observations) {
    // The DOA's azimuth in the array frame for this tentative's side of the cone.
    const double az = (obs.mirrored && best_mirror) ? -obs.z[0] : obs.z[0];
    Birth(utime, best_key, obs, az);
  }
}

void OnlineSoundMap::Birth(int64_t utime, int64_t key, const Obs& obs, double azimuth_rad) {
  const Tentative t = tentatives_.at(key);
  auto make = [&](const Tentative& from, double az) {
    const int64_t source = next_source_id_++;
    const int64_t anchor = AnchorForBirth();
    Eigen::VectorXd z = obs.z;
    z[0] = az;
    ekf_.AddSource(source, anchor, z, obs.r);
    Meta& m = meta_[source];
    m.first = from.first;
    m.last = utime;
    m.n = from.n;
    ++counters_.doa_new_sources;
    ++counters_.doa_used;
    if (from.track_id >= 0) associator_.Commit(from.device, from.track_id, source, {});
    return source;
  };
  const int64_t a = make(t, azimuth_rad);
  auto tw = tentatives_.find(t.twin);
  if (tw != tentatives_.end()) {
    const int64_t b = make(tw->second, -azimuth_rad);
    meta_[a].twin = b;
    meta_[b].twin = a;
    tentatives_.erase(tw);
  }
  tentatives_.erase(key);
}

void OnlineSoundMap::Remove(int64_t source) {
  if (!ekf_.HasSource(source)) return;
  const int64_t anchor = ekf_.source_anchor(source);
  ekf_.RemoveSource(source);
  bool anchor_used = false;
  for (int64_t s : ekf_.source_ids()) anchor_used = anchor_used || ekf_.source_anchor(s) == anchor;
  if (!anchor_used) {
    ekf_.RemoveAnchor(anchor);
    if (anchor_links_.erase(anchor)) anchors_changed_ = true;
  }
  auto it = meta_.find(source);
  if (it != meta_.end()) {
    auto tw = meta_.find(it->second.twin);
    if (tw != meta_.end()) tw->second.twin = -1;
    meta_.erase(it);
  }
}

void OnlineSoundMap::Prune(int64_t utime) {
  const int64_t after = static_cast<int64_t>(options_.prune_after_s * 1e6);
  std::vector<int64_t> drop;
  for (int64_t id : ekf_.source_ids()) {
    const Meta& m = meta_[id];
    if (m.n < options_.prune_min_observations && utime - m.last > after && !Converged(id)) {
      drop.push_back(id);
      continue;
    }
    double rho = 0, var = 0;
    ekf_.SourceInverseDepth(id, &rho, &var);
    if (options_.prune_behind_sigmas > 0 &&
        rho < -options_.prune_behind_sigmas * std::sqrt(std::max(0.0, var))) {
      drop.push_back(id);
      ++counters_.sources_behind;
      continue;
    }
    if (options_.path_clearance_m > 0 && Converged(id)) {
      Eigen::Vector3d point;
      Eigen::Matrix3d cov;
      ekf_.SourcePoint(id, &point, &cov);
      if (OnTrail(point.head<2>())) {
        drop.push_back(id);
        ++counters_.sources_on_path;
      }
    }
  }
  for (int64_t id : drop) {
    Remove(id);
    ++counters_.sources_pruned;
  }
}

void OnlineSoundMap::OnHeardPerson(const std::string& device, int64_t track_id, bool called) {
  const int64_t s = associator_.SourceOfTrack(device, track_id);
  if (s >= 0 && ekf_.HasSource(s)) {
    meta_[s].is_person = true;
    meta_[s].called |= called;
    const int64_t twin = meta_[s].twin;
    if (twin >= 0 && ekf_.HasSource(twin)) {
      meta_[twin].is_person = true;
      meta_[twin].called |= called;
    }
  }
}

void OnlineSoundMap::SetSite(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m) {
  if (!min_m.allFinite() || !max_m.allFinite() || (max_m.array() < min_m.array()).any()) return;
  have_site_ = true;
  site_min_ = min_m;
  site_max_ = max_m;
}

int64_t OnlineSoundMap::OnHeardDirection(const Doa& doa) {
  Obs obs;
  if (!have_pose_ || !MakeObs(doa, &obs)) return -1;
  AddRay(last_pose_utime_, doa, true);
  int64_t best = -1;
  double best_chi2 = options_.gate_chi2;
  for (int64_t id : ekf_.source_ids()) {
    const double c = Chi2(id, obs, nullptr);
    if (c <= best_chi2) {
      best_chi2 = c;
      best = id;
    }
  }
  if (best < 0) return -1;
  meta_[best].is_person = true;
  meta_[best].called |= doa.called;
  const int64_t twin = meta_[best].twin;
  if (twin >= 0 && ekf_.HasSource(twin)) {
    meta_[twin].is_person = true;
    meta_[twin].called |= doa.called;
  }
  return best;
}

std::vector<int64_t> OnlineSoundMap::AnchorNodeIds() const {
  std::set<int64_t> ids;
  for (int64_t s : ekf_.source_ids()) {
    auto link = anchor_links_.find(ekf_.source_anchor(s));
    if (link != anchor_links_.end()) ids.insert(link->second.node);
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

void OnlineSoundMap::Classify(const std::array<double, 5>& class_votes, bool heard, bool called,
                              Source* s) const {
  int best_class = kClassUnknown;
  double votes = 0;
  for (int k = 1; k < 5; ++k) {
    votes += class_votes[k];
    if (class_votes[k] > (best_class ? class_votes[best_class] : 0.0)) best_class = k;
  }
  if (votes < options_.min_class_votes) best_class = kClassUnknown;
  s->sound_class = best_class;
  s->class_confidence = best_class != kClassUnknown ? class_votes[best_class] / votes : 0.0;
  s->priority =
      best_class == kClassVoice ? (called ? kPriorityCall : kPriorityVoice) : kPriorityNone;
  const Eigen::Array2d xy = s->position_m.head<2>().array();
  s->inside_site = !have_site_ || ((xy >= site_min_.array() - options_.site_margin_m).all() &&
                                   (xy <= site_max_.array() + options_.site_margin_m).all());
  // Only a placed voice inside the site is a person; machines and alarms never are.
  s->is_person = heard && best_class == kClassVoice &&
                 s->class_confidence >= options_.person_min_voice_share && s->has_position &&
                 s->inside_site;
}

std::vector<OnlineSoundMap::Source> OnlineSoundMap::Sources(int64_t now) const {
  std::vector<Source> out;
  for (int64_t id : ekf_.source_ids()) {
    Source s;
    s.id = id;
    ekf_.SourcePoint(id, &s.position_m, &s.covariance);
    const Meta& m = meta_.at(id);
    // Range observability: the inverse depth is known to be positive by observable_sigmas,
    // and the planar position is settled to max_position_sigma_m.
    double rho = 0, rho_var = 0;
    ekf_.SourceInverseDepth(id, &rho, &rho_var);
    const Eigen::Matrix2d c =
        0.5 * (s.covariance.topLeftCorner<2, 2>() + s.covariance.topLeftCorner<2, 2>().transpose());
    const double half_trace = 0.5 * c.trace();
    const double largest =
        half_trace + std::sqrt(std::max(0.0, half_trace * half_trace - c.determinant()));
    s.has_position = s.position_m.allFinite() && std::isfinite(largest) &&
                     rho > options_.observable_sigmas * std::sqrt(std::max(rho_var, 0.0)) &&
                     std::sqrt(largest) <= options_.max_position_sigma_m;
    ekf_.SourceBearing(id, &s.bearing_rad, &s.bearing_variance);
    {
      const Pose2 anchor = ekf_.anchor(ekf_.source_anchor(id));
      double a[3] = {anchor.x, anchor.y, anchor.yaw}, o[2];
      ArrayOrigin(a, ekf_.options().mount, o);
      s.bearing_origin_m = Eigen::Vector3d(o[0], o[1], ekf_.options().mount.z_m);
    }
    if (!s.has_position) {
      s.position_m = s.bearing_origin_m;
      s.covariance.setZero();
      s.covariance.topLeftCorner<2, 2>() =
          ekf_.anchor_covariance(ekf_.source_anchor(id)).topLeftCorner<2, 2>();
    }
    Classify(m.class_votes, m.is_person, m.called, &s);
    s.first_heard_utime = m.first;
    s.last_heard_utime = m.last;
    s.num_observations = m.n;
    s.hypotheses_left = (m.twin >= 0 && ekf_.HasSource(m.twin)) ? 2 : 1;
    s.state = Converged(id) ? Source::kConverged : Source::kInitialising;
    if (now - m.last > static_cast<int64_t>(options_.silent_after_s * 1e6))
      s.state = Source::kSilent;
    out.push_back(s);
  }
  // Sources where the bearings cross that no placed EKF source explains.
  const size_t num_ekf = out.size();
  std::vector<bool> superseded(num_ekf, false);
  const double z = ekf_.options().mount.z_m;
  for (size_t k = 0; k < evidence_sources_.size(); ++k) {
    const BearingEvidence::Source& e = evidence_sources_[k];
    // Where the robot drove: the robot's own noise or a ghost, as for the EKF's sources.
    if (options_.path_clearance_m > 0 && OnTrail(e.position_m)) continue;
    // Explained by an EKF source placed at least as well. A looser EKF source nearby is the
    // same emitter placed worse: this one replaces it (one source per emitter, taking over
    // whether it was heard calling).
    bool explained = false;
    std::vector<size_t> looser;
    for (size_t j = 0; j < num_ekf; ++j) {
      if (!out[j].has_position ||
          (out[j].position_m.head<2>() - e.position_m).norm() >= options_.evidence.merge_radius_m)
        continue;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(
          out[j].covariance.topLeftCorner<2, 2>());
      if (std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff())) <=
          std::max(e.largest_sigma_m, options_.converged_sigma_m))
        explained = true;
      else
        looser.push_back(j);
    }
    if (explained) continue;
    bool heard = e.heard, called = e.called;
    if (e.largest_sigma_m <= options_.max_position_sigma_m) {
      for (size_t j : looser) {
        superseded[j] = true;
        const Meta& m = meta_.at(out[j].id);
        heard |= m.is_person;
        called |= m.called;
      }
    }
    Source s;
    s.id = evidence_ids_[k];
    s.position_m = Eigen::Vector3d(e.position_m.x(), e.position_m.y(), z);
    s.covariance = Eigen::Matrix3d::Zero();
    s.covariance.topLeftCorner<2, 2>() = e.covariance;
    s.has_position = e.largest_sigma_m <= options_.max_position_sigma_m;
    s.bearing_origin_m = Eigen::Vector3d(e.nearest_origin_m.x(), e.nearest_origin_m.y(), z);
    const Eigen::Vector2d to = e.position_m - e.nearest_origin_m;
    s.bearing_rad = std::atan2(to.y(), to.x());
    s.bearing_variance = 0;
    if (!s.has_position) {
      s.position_m = s.bearing_origin_m;
      s.covariance.setZero();
    }
    Classify(e.class_votes, heard, called, &s);
    s.first_heard_utime = e.first_utime;
    s.last_heard_utime = e.last_utime;
    s.num_observations = static_cast<int>(std::lround(e.rays));
    s.state =
        e.largest_sigma_m < options_.converged_sigma_m ? Source::kConverged : Source::kInitialising;
    if (now - e.last_utime > static_cast<int64_t>(options_.silent_after_s * 1e6))
      s.state = Source::kSilent;
    out.push_back(s);
  }
  std::vector<Source> kept;
  kept.reserve(out.size());
  for (size_t j = 0; j < out.size(); ++j) {
    if (j < num_ekf && superseded[j]) continue;
    Source& s = out[j];
    // A position beyond the mapped site (and its margin) is a reflection's crossing or a range
    // the bearings do not really fix: it goes out as the bearing it was heard on, never as a
    // place (Classify has already kept it from being a person).
    if (s.has_position && !s.inside_site) {
      s.has_position = false;
      s.position_m = s.bearing_origin_m;
      s.covariance.setZero();
      if (j < num_ekf) {
        s.covariance.topLeftCorner<2, 2>() =
            ekf_.anchor_covariance(ekf_.source_anchor(s.id)).topLeftCorner<2, 2>();
      }
    }
    kept.push_back(std::move(s));
  }
  return kept;
}

// ---------------------------------------------------------------------------------------
// State file: little-endian binary, "SARMAPSM" + version, then the state field by field.

namespace {
constexpr char kStateMagic[8] = {'S', 'A', 'R', 'M', 'A', 'P', 'S', 'M'};
constexpr int32_t kStateVersion = 3;        // 2: class votes and calls per source; 3: bearing rays
constexpr char kStateKind[] = "sound-map";  // the seal's kind (common/state_file.h)

void WritePose(common::BinaryWriter* w, const Pose2& p) { w->Pod(p.x), w->Pod(p.y), w->Pod(p.yaw); }
Pose2 ReadPose(common::BinaryReader* r) {
  const double x = r->Pod<double>(), y = r->Pod<double>(), yaw = r->Pod<double>();
  return Pose2(x, y, yaw);
}
}  // namespace

void OnlineSoundMap::Save(const std::string& path) const {
  common::SealedStateWriter file(path, kStateKind, kStateVersion);  // streamed to disk
  common::BinaryWriter writer(&file.body());
  const auto write = [this](common::BinaryWriter* w) {
    for (char c : kStateMagic) w->Pod(c);
    w->Pod(kStateVersion);
    w->Pod<int8_t>(options_.three_d);
    ekf_.Save(w);
    associator_.Save(w);
    w->Pod<int64_t>(static_cast<int64_t>(tentatives_.size()));
    for (const auto& [key, t] : tentatives_) {
      w->Pod(key), w->Pod(t.first), w->Pod(t.last), w->Pod(t.bearing_map_rad), w->Pod(t.variance);
      w->Pod<int32_t>(t.n), w->Pod(t.track_id), w->Pod(t.twin);
      w->String(t.device);
    }
    w->Pod(next_tentative_);
    w->Pod<int8_t>(have_pose_);
    WritePose(w, last_pose_);
    w->Pod(last_pose_utime_), w->Pod(yaw_rate_rad_per_s_), w->Pod(last_node_id_);
    w->Pod(next_local_anchor_), w->Pod(next_source_id_), w->Pod(next_anchor_id_);
    w->Pod<int64_t>(static_cast<int64_t>(meta_.size()));
    for (const auto& [id, m] : meta_) {
      w->Pod(id), w->Pod<int8_t>(m.is_person), w->Pod(m.first), w->Pod(m.last);
      w->Pod<int32_t>(m.n), w->Pod(m.twin), w->Pod<int32_t>(m.mirror_misses);
      w->Pod<int8_t>(m.called);
      for (double v : m.class_votes) w->Pod(v);
    }
    w->Pod(counters_);
    w->Pod<int64_t>(static_cast<int64_t>(anchor_links_.size()));
    for (const auto& [id, link] : anchor_links_)
      w->Pod(id), w->Pod(link.node), WritePose(w, link.node_from_anchor);
    w->Pod<int64_t>(static_cast<int64_t>(node_poses_.size()));
    for (const auto& [id, pose] : node_poses_) w->Pod(id), WritePose(w, pose);
    w->Pod<int64_t>(static_cast<int64_t>(trail_cells_.size()));
    for (const auto& [cell, points] : trail_cells_) {
      w->Pod(cell), w->Pod<int64_t>(static_cast<int64_t>(points.size()));
      for (const auto& p : points) w->Pod(p.x()), w->Pod(p.y());
    }
    w->Pod(last_trail_point_.x()), w->Pod(last_trail_point_.y());
    evidence_.Save(w);
    w->Pod(next_evidence_id_);
    for (char c : kStateMagic) w->Pod(c);  // trailer: a complete file
  };
  write(&writer);
  file.Commit();  // throws if any write failed
}

bool OnlineSoundMap::Load(const std::string& path) {
  std::string body;
  // Throws StateFileError (another kind or version, truncated, bit flips) before any parsing.
  if (common::ReadSealedState(path, kStateKind, kStateVersion, &body) ==
      common::StateFileRead::kMissing)
    return false;
  common::MemoryStreamBuffer bytes(body.data(), body.size());  // read in place, not copied
  std::istream in(&bytes);
  common::BinaryReader r(&in, "sound-map state '" + path + "'");
  auto magic = [&r] {
    for (char c : kStateMagic)
      if (r.Pod<char>() != c) r.Corrupt("not a sound-map state file");
  };
  magic();
  if (r.Pod<int32_t>() != kStateVersion) r.Corrupt("unknown version");
  if ((r.Pod<int8_t>() != 0) != options_.three_d)
    r.Corrupt("saved by a map with the other three_d");
  // Read into a fresh map and swap, so a bad file leaves this one untouched.
  OnlineSoundMap m(options_, ekf_.options().mount);
  m.ekf_.Load(&r);
  m.associator_.Load(&r);
  const int64_t num_tentatives = r.Count(1000000);
  for (int64_t k = 0; k < num_tentatives; ++k) {
    const int64_t key = r.Pod<int64_t>();
    Tentative& t = m.tentatives_[key];
    t.first = r.Pod<int64_t>(), t.last = r.Pod<int64_t>();
    t.bearing_map_rad = r.Pod<double>(), t.variance = r.Pod<double>();
    t.n = r.Pod<int32_t>(), t.track_id = r.Pod<int64_t>(), t.twin = r.Pod<int64_t>();
    t.device = r.String();
  }
  m.next_tentative_ = r.Pod<int64_t>();
  m.have_pose_ = r.Pod<int8_t>() != 0;
  m.last_pose_ = ReadPose(&r);
  m.last_pose_utime_ = r.Pod<int64_t>(), m.yaw_rate_rad_per_s_ = r.Pod<double>();
  m.last_node_id_ = r.Pod<int64_t>();
  m.next_local_anchor_ = r.Pod<int64_t>(), m.next_source_id_ = r.Pod<int64_t>();
  m.next_anchor_id_ = r.Pod<int64_t>();
  const int64_t num_meta = r.Count(1000000);
  for (int64_t k = 0; k < num_meta; ++k) {
    Meta& meta = m.meta_[r.Pod<int64_t>()];
    meta.is_person = r.Pod<int8_t>() != 0;
    meta.first = r.Pod<int64_t>(), meta.last = r.Pod<int64_t>();
    meta.n = r.Pod<int32_t>(), meta.twin = r.Pod<int64_t>(), meta.mirror_misses = r.Pod<int32_t>();
    meta.called = r.Pod<int8_t>() != 0;
    for (double& v : meta.class_votes) v = r.Pod<double>();
  }
  m.counters_ = r.Pod<Counters>();
  const int64_t num_links = r.Count(1000000);
  for (int64_t k = 0; k < num_links; ++k) {
    AnchorLink& link = m.anchor_links_[r.Pod<int64_t>()];
    link.node = r.Pod<int64_t>();
    link.node_from_anchor = ReadPose(&r);
  }
  const int64_t num_nodes = r.Count(10000000);
  for (int64_t k = 0; k < num_nodes; ++k) {
    const int64_t id = r.Pod<int64_t>();
    m.node_poses_[id] = ReadPose(&r);
  }
  const int64_t num_cells = r.Count(10000000);
  for (int64_t k = 0; k < num_cells; ++k) {
    auto& points = m.trail_cells_[r.Pod<int64_t>()];
    points.resize(static_cast<size_t>(r.Count(10000000)));
    for (auto& p : points) p.x() = r.Pod<double>(), p.y() = r.Pod<double>();
  }
  m.last_trail_point_.x() = r.Pod<double>(), m.last_trail_point_.y() = r.Pod<double>();
  m.evidence_.Load(&r);
  m.next_evidence_id_ = r.Pod<int64_t>();
  magic();
  for (const auto& [id, meta] : m.meta_)
    if (!m.ekf_.HasSource(id)) r.Corrupt("source " + std::to_string(id) + " not in the EKF");
  // A restarted node asks SLAM to keep its anchors again.
  m.anchors_changed_ = true;
  *this = std::move(m);
  return true;
}

}  // namespace sound_map
}  // namespace sarmap
