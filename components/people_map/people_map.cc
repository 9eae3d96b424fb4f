#include "people_map/people_map.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "common/state_file.h"

namespace sarmap {
namespace people_map {
namespace {

using common::Utime;

// A person merged into another: `into` counts `from`'s detections and keeps the higher
// confidence, the confirmation and the whole time span of both.
void AddDetectionsOf(const Person& from, Person* into) {
  into->num_detections += from.num_detections;
  into->confidence = std::max(into->confidence, from.confidence);
  into->confirmed = into->confirmed || from.confirmed;
  into->first_detected_utime = std::min(into->first_detected_utime, from.first_detected_utime);
  into->last_detected_utime = std::max(into->last_detected_utime, from.last_detected_utime);
}

// Clamps the eigenvalues of a covariance from below (repeated detections share the pose
// error, so fusion must not make a person arbitrarily certain).
Eigen::Matrix3d Floor(const Eigen::Matrix3d& cov, double min_variance) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(0.5 * (cov + cov.transpose()));
  const Eigen::Vector3d values = eig.eigenvalues().cwiseMax(min_variance);
  return eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}

// Product of two Gaussians in covariance form, x = xa + K (xb - xa), P = (I - K) Pa with
// K = Pa (Pa + Pb)^-1: unlike the information form it takes a covariance that is singular in one
// direction (a planar sound source says nothing about height, z variance 0). If the sum is
// singular too, a's estimate stands.
void Fuse(const Eigen::Vector3d& xa, const Eigen::Matrix3d& Pa, const Eigen::Vector3d& xb,
          const Eigen::Matrix3d& Pb, Eigen::Vector3d* x, Eigen::Matrix3d* P) {
  const Eigen::Matrix3d S = Pa + Pb;
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(S);
  if (!lu.isInvertible()) {
    *x = xa;
    *P = Pa;
    return;
  }
  const Eigen::Matrix3d K = Pa * lu.inverse();
  const Eigen::Vector3d fused_x = xa + K * (xb - xa);
  Eigen::Matrix3d fused_P = (Eigen::Matrix3d::Identity() - K) * Pa;
  fused_P = 0.5 * (fused_P + fused_P.transpose());
  if (!fused_x.allFinite() || !fused_P.allFinite()) {
    *x = xa;
    *P = Pa;
    return;
  }
  *x = fused_x;
  *P = fused_P;
}

double PlanarMahalanobis2(const Eigen::Vector3d& a, const Eigen::Matrix3d& Pa,
                          const Eigen::Vector3d& b, const Eigen::Matrix3d& Pb) {
  const Eigen::Vector2d d = (a - b).head<2>();
  const Eigen::Matrix2d S = Pa.topLeftCorner<2, 2>() + Pb.topLeftCorner<2, 2>();
  return d.dot(S.ldlt().solve(d));
}

YAML::Node Vec(const Eigen::Vector3d& v) {
  YAML::Node n;
  for (int i = 0; i < 3; ++i) n.push_back(v[i]);
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}
YAML::Node Mat(const Eigen::Matrix3d& m) {
  YAML::Node n;
  for (int i = 0; i < 9; ++i) n.push_back(m(i / 3, i % 3));
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}
Eigen::Vector3d ToVec(const YAML::Node& n) {
  if (!n.IsSequence() || n.size() != 3) throw std::runtime_error("expected 3 numbers");
  return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}
Eigen::Matrix3d ToMat(const YAML::Node& n) {
  if (!n.IsSequence() || n.size() != 9) throw std::runtime_error("expected 9 numbers");
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = n[i].as<double>();
  return m;
}

}  // namespace

double PeopleMap::DecayedConfidence(const Person& p, Utime utime) const {
  const double age_s = std::max<double>(0.0, common::UtimeToSeconds(utime - p.last_detected_utime));
  return p.confidence * std::pow(0.5, age_s / options_.confidence_half_life_s);
}

bool PeopleMap::Reported(const Person& p, Utime utime) const {
  if (!p.has_heard) {
    // num_detections of a person never heard counts the frames they were seen in.
    const bool enough_frames = p.num_detections >= options_.min_seen_detections;
    const bool seen_again =
        options_.min_seen_span_s > 0 &&
        common::UtimeToSeconds(p.last_detected_utime - p.first_detected_utime) >=
            options_.min_seen_span_s;
    if (!enough_frames && !seen_again) return false;
  }
  return p.confirmed || DecayedConfidence(p, utime) >= options_.min_report_confidence;
}

void PeopleMap::AddEvidence(Person* p, Utime utime, double detection_confidence) const {
  const double c = DecayedConfidence(*p, utime);
  const double cd = std::clamp(detection_confidence, 0.0, 1.0);
  p->confidence = 1.0 - (1.0 - c) * (1.0 - options_.confidence_gain * cd);
  p->confirmed = p->confirmed || p->confidence >= options_.keep_confidence;
  p->last_detected_utime = std::max(p->last_detected_utime, utime);
  ++p->num_detections;
}

void PeopleMap::Refuse(Person* p) const {
  if (p->has_seen && p->has_heard) {
    // The heard estimate comes with the change of SLAM's pose error since the sighting (see
    // HeardSeenMahalanobis2), as the gate that joined them took it.
    Fuse(p->seen_position_m, p->seen_covariance, p->heard_position_m,
         p->heard_covariance + RelativePoseCovariance(), &p->position_m, &p->covariance);
  } else if (p->has_seen) {
    p->position_m = p->seen_position_m;
    p->covariance = p->seen_covariance;
  } else if (p->has_heard) {
    p->position_m = p->heard_position_m;
    p->covariance = p->heard_covariance;
  }
}

Person* PeopleMap::NearestSeen(const Eigen::Vector3d& position_m, double radius_m) {
  Person* best = nullptr;
  double best_d = radius_m;
  for (auto& [id, p] : people_) {
    if (!p.has_seen) continue;
    const double d = (p.seen_position_m - position_m).head<2>().norm();
    if (d <= best_d) {
      best_d = d;
      best = &p;
    }
  }
  return best;
}

bool PeopleMap::SettledWithSighting(const Person& p, Eigen::Vector3d* x_out,
                                    Eigen::Matrix3d* P_out) const {
  // The current sighting: its detections' information-weighted mean, with their averaged
  // sensor noise plus the sighting's one pose error; fused with what earlier sightings settled.
  const double min_var = options_.min_position_sigma_m * options_.min_position_sigma_m;
  const Eigen::Matrix3d sensor = p.sighting_information.inverse();
  const Eigen::Vector3d x = sensor * p.sighting_information_position;
  const Eigen::Matrix3d P = Floor(sensor + p.sighting_pose_covariance, min_var);
  if (!x.allFinite() || !P.allFinite()) return false;
  if (!p.has_settled) {
    *x_out = x;
    *P_out = P;
    return true;
  }
  Eigen::Matrix3d fused_P;
  Fuse(p.settled_position_m, p.settled_covariance, x, P, x_out, &fused_P);
  *P_out = Floor(fused_P, min_var);
  return true;
}

void PeopleMap::CloseSighting(Person* p) const {
  if (p->sighting_detections == 0) return;
  Eigen::Vector3d x;
  Eigen::Matrix3d P;
  if (SettledWithSighting(*p, &x, &P)) {
    p->settled_position_m = x;
    p->settled_covariance = P;
    p->has_settled = true;
  }
  p->sighting_track_id = -1;
  p->sighting_detections = 0;
  p->sighting_information.setZero();
  p->sighting_information_position.setZero();
  p->sighting_pose_covariance.setZero();
}

void PeopleMap::UpdateSeen(Person* p) const {
  if (p->sighting_detections == 0) {
    if (!p->has_settled) return;
    p->seen_position_m = p->settled_position_m;
    p->seen_covariance = p->settled_covariance;
    return;
  }
  Eigen::Vector3d x;
  Eigen::Matrix3d P;
  if (!SettledWithSighting(*p, &x, &P)) return;
  p->seen_position_m = x;
  p->seen_covariance = P;
}

void PeopleMap::AddSeen(Utime utime, const std::vector<SeenDetection>& detections,
                        const common::Rigid3d& map_from_camera,
                        const Eigen::Matrix3d& pose_covariance, const Eigen::Vector2d& robot_xy,
                        const PoseNode& node) {
  const Eigen::Matrix3d R = map_from_camera.rotation().toRotationMatrix();
  const double min_var = options_.min_position_sigma_m * options_.min_position_sigma_m;
  std::map<int64_t, int> count_this_frame;
  for (const auto& d : detections) {
    const Eigen::Vector3d z = map_from_camera * d.position_camera_m;
    // d z / d (x, y, yaw) of the robot pose.
    Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
    J(0, 0) = 1;
    J(1, 1) = 1;
    J(0, 2) = -(z.y() - robot_xy.y());
    J(1, 2) = z.x() - robot_xy.x();
    const Eigen::Matrix3d sensor = Floor(R * d.covariance_camera * R.transpose(), min_var);
    const Eigen::Matrix3d pose_part = J * pose_covariance * J.transpose();
    const Eigen::Matrix3d Pz = Floor(sensor + pose_part, min_var);

    // The person this detection's track is a sighting of, while the track goes on and stays
    // within one place of it; else the nearest seen person within merge_radius_m.
    Person* p = nullptr;
    if (d.track_id >= 0) {
      for (auto& [id, q] : people_) {
        if (q.has_seen && q.sighting_track_id == d.track_id && q.sighting_detections > 0 &&
            common::UtimeToSeconds(utime - q.sighting_last_utime) <= options_.track_gap_s &&
            (q.seen_position_m - z).head<2>().norm() <= options_.merge_radius_m) {
          p = &q;
          break;
        }
      }
    }
    if (!p) p = NearestSeen(z, options_.merge_radius_m);
    if (!p && options_.relative_pose_sigma_m > 0) {
      // A new sighting of someone seen before, SLAM's pose error having changed in between. Not
      // a person seen in this same frame: detections of one frame share one pose error, so
      // their distance apart is real.
      const Eigen::Matrix3d drift =
          Eigen::Vector3d(1, 1, 0).asDiagonal() *
          (options_.relative_pose_sigma_m * options_.relative_pose_sigma_m);
      double best = options_.sighting_gate_chi2;
      for (auto& [id, q] : people_) {
        if (!q.has_seen || count_this_frame.count(id)) continue;
        const double m2 = PlanarMahalanobis2(q.seen_position_m, q.seen_covariance + drift, z, Pz);
        if (m2 <= best) {
          best = m2;
          p = &q;
        }
      }
    }
    if (p) {
      if (d.track_id < 0 || d.track_id != p->sighting_track_id) CloseSighting(p);
    } else {
      // A heard-only person this seen one agrees with: one person, both cues.
      for (auto& [id, q] : people_) {
        if (q.has_seen || !q.has_heard) continue;
        if (HeardAgreesWithSeen(z, Pz, q.heard_position_m, q.heard_covariance)) {
          p = &q;
          break;
        }
      }
      if (!p) p = NewPerson(utime);
      p->has_seen = true;
      p->has_settled = false;
    }
    // The detection joins the person's current sighting: its sensor noise is independent of the
    // sighting's other detections, its pose error is not (one viewing, one pose error).
    const Eigen::Matrix3d information = sensor.inverse();
    p->sighting_track_id = d.track_id;
    p->sighting_last_utime = utime;
    ++p->sighting_detections;
    p->sighting_information += information;
    p->sighting_information_position += information * z;
    p->sighting_pose_covariance = pose_part;
    UpdateSeen(p);
    if (d.track_id < 0) CloseSighting(p);  // no track: a sighting of its own
    if (seen_trace_)
      seen_trace_({utime, z, Pz, d.position_camera_m, p->id, p->num_detections == 0});
    p->cues |= d.cue;
    // A person nobody reports (a candidate, or one whose confidence has decayed) holds no SLAM
    // node (AnchorNodeIds): it hangs from the node of its latest sighting until it is reported.
    if ((p->anchor_node_id < 0 || !Reported(*p, utime)) && node.node_id >= 0) {
      p->anchor_node_id = node.node_id;
      p->map_from_anchor_node = node.map_from_node;
    }
    AddEvidence(p, utime, d.confidence);
    p->people_count = std::max(p->people_count, ++count_this_frame[p->id]);
    Refuse(p);
  }
  MergeCloseSeenPeople();
}

void PeopleMap::MergeCloseSeenPeople() {
  const double min_var = options_.min_position_sigma_m * options_.min_position_sigma_m;
  for (auto a = people_.begin(); a != people_.end(); ++a) {
    if (!a->second.has_seen) continue;
    for (auto b = std::next(a); b != people_.end();) {
      Person& pa = a->second;
      Person& pb = b->second;
      if (!pb.has_seen ||
          (pa.seen_position_m - pb.seen_position_m).head<2>().norm() > options_.merge_radius_m ||
          (pa.has_heard && pb.has_heard && pa.sound_source_id != pb.sound_source_id)) {
        ++b;
        continue;
      }
      // Both people's sightings so far are settled, then one fused with the other.
      CloseSighting(&pa);
      CloseSighting(&pb);
      Eigen::Vector3d x;
      Eigen::Matrix3d P;
      Fuse(pa.seen_position_m, pa.seen_covariance, pb.seen_position_m, pb.seen_covariance, &x, &P);
      pa.seen_position_m = x;
      pa.seen_covariance = Floor(P, min_var);
      pa.settled_position_m = x;
      pa.settled_covariance = pa.seen_covariance;
      pa.has_settled = true;
      pa.cues |= pb.cues;
      pa.num_detections += pb.num_detections;
      pa.people_count = std::max(pa.people_count, pb.people_count);
      pa.confidence = std::max(pa.confidence, pb.confidence);
      pa.confirmed = pa.confirmed || pb.confirmed;
      if (pa.anchor_node_id < 0) {
        pa.anchor_node_id = pb.anchor_node_id;
        pa.map_from_anchor_node = pb.map_from_anchor_node;
      }
      pa.first_detected_utime = std::min(pa.first_detected_utime, pb.first_detected_utime);
      pa.last_detected_utime = std::max(pa.last_detected_utime, pb.last_detected_utime);
      if (!pa.has_heard && pb.has_heard) {
        pa.has_heard = true;
        pa.heard_position_m = pb.heard_position_m;
        pa.heard_covariance = pb.heard_covariance;
        pa.sound_source_id = pb.sound_source_id;
        pa.keyword = pb.keyword;
      }
      Refuse(&pa);
      b = people_.erase(b);
    }
  }
}

int PeopleMap::MoveWithNodes(const std::map<int64_t, common::Rigid2d>& map_from_node) {
  int moved = 0;
  for (auto& [id, p] : people_) {
    if (!p.has_seen || p.anchor_node_id < 0) continue;
    const auto node = map_from_node.find(p.anchor_node_id);
    if (node == map_from_node.end()) continue;
    // The node's correction C = T_new T_old^-1 carries what was placed from it: x' = R x + t,
    // P' = R P R^T; a sighting's information sums go as I' = R I R^T, (I x)' = R (I x) + I' t.
    const common::Rigid2d correction = node->second * p.map_from_anchor_node.inverse();
    const Eigen::Vector3d t(correction.translation().x(), correction.translation().y(), 0.0);
    if (!t.allFinite() || !std::isfinite(correction.yaw_rad())) continue;
    p.map_from_anchor_node = node->second;
    if (t.norm() < 1e-9 && std::abs(correction.yaw_rad()) < 1e-12) continue;
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(correction.yaw_rad(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p.seen_position_m = R * p.seen_position_m + t;
    p.seen_covariance = R * p.seen_covariance * R.transpose();
    p.settled_position_m = R * p.settled_position_m + t;
    p.settled_covariance = R * p.settled_covariance * R.transpose();
    p.sighting_information = R * p.sighting_information * R.transpose();
    p.sighting_information_position =
        R * p.sighting_information_position + p.sighting_information * t;
    p.sighting_pose_covariance = R * p.sighting_pose_covariance * R.transpose();
    Refuse(&p);
    ++moved;
  }
  if (moved > 0) MergeCloseSeenPeople();
  return moved;
}

std::vector<int64_t> PeopleMap::AnchorNodeIds(size_t max_nodes, common::Utime now) const {
  std::vector<const Person*> anchored;
  for (const auto& [id, p] : people_) {
    if (!p.has_seen || p.anchor_node_id < 0) continue;
    if (now >= 0 && !Reported(p, now)) continue;
    anchored.push_back(&p);
  }
  if (max_nodes > 0 && anchored.size() > max_nodes) {
    // Every kept anchor costs SLAM three rows of the joint covariance it publishes.
    std::sort(anchored.begin(), anchored.end(), [](const Person* a, const Person* b) {
      if (a->confirmed != b->confirmed) return a->confirmed;
      return a->last_detected_utime > b->last_detected_utime;
    });
  }
  std::vector<int64_t> ids;
  for (const Person* p : anchored) {
    if (max_nodes > 0 && ids.size() >= max_nodes) break;
    if (std::find(ids.begin(), ids.end(), p->anchor_node_id) == ids.end())
      ids.push_back(p->anchor_node_id);
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

void PeopleMap::ForgetAnchors() {
  for (auto& [id, p] : people_) p.anchor_node_id = -1;
}

bool PeopleMap::HeardAgreesWithSeen(const Eigen::Vector3d& seen_m,
                                    const Eigen::Matrix3d& seen_covariance,
                                    const Eigen::Vector3d& heard_m,
                                    const Eigen::Matrix3d& heard_covariance) const {
  return (seen_m - heard_m).head<2>().norm() <= options_.fuse_max_distance_m &&
         HeardSeenMahalanobis2(seen_m, seen_covariance, heard_m, heard_covariance) <=
             options_.fuse_gate_chi2;
}

Person* PeopleMap::NewPerson(common::Utime utime) {
  Person fresh;
  fresh.id = next_id_++;
  fresh.first_detected_utime = utime;
  fresh.last_detected_utime = utime;
  return &people_.emplace(fresh.id, fresh).first->second;
}

double PeopleMap::HeardSeenMahalanobis2(const Eigen::Vector3d& seen_m,
                                        const Eigen::Matrix3d& seen_covariance,
                                        const Eigen::Vector3d& heard_m,
                                        const Eigen::Matrix3d& heard_covariance) const {
  // The sound map places a voice from bearings along a stretch of the path, the camera from
  // another: the change of SLAM's pose error between them separates the two estimates as it
  // separates two sightings.
  return PlanarMahalanobis2(seen_m, seen_covariance + RelativePoseCovariance(), heard_m,
                            heard_covariance);
}

Eigen::Matrix3d PeopleMap::RelativePoseCovariance() const {
  return Eigen::Vector3d(1, 1, 0).asDiagonal() *
         (options_.relative_pose_sigma_m * options_.relative_pose_sigma_m);
}

int PeopleMap::RecentCalls(int64_t source_id, Utime utime) const {
  const auto it = source_call_utimes_.find(source_id);
  if (it == source_call_utimes_.end()) return 0;
  int count = 0;
  for (Utime t : it->second) {
    if (std::abs(common::UtimeToSeconds(utime - t)) <= options_.heard_person_window_s) ++count;
  }
  return count;
}

bool PeopleMap::Placed(const SoundSource& s) const {
  if (!options_.heard_needs_converged_source || s.converged) return true;
  if (options_.heard_max_source_sigma_m <= 0) return false;
  // Largest eigenvalue of the planar covariance.
  const Eigen::Matrix2d c =
      0.5 * (s.covariance.topLeftCorner<2, 2>() + s.covariance.topLeftCorner<2, 2>().transpose());
  const double half_trace = 0.5 * c.trace();
  const double largest =
      half_trace + std::sqrt(std::max(0.0, half_trace * half_trace - c.determinant()));
  return std::isfinite(largest) && std::sqrt(largest) <= options_.heard_max_source_sigma_m;
}

int PeopleMap::AddHeard(Utime utime, const std::vector<HeardDetection>& detections,
                        const common::Rigid3d& map_from_mic) {
  const Eigen::Vector3d origin = map_from_mic.translation();
  const common::Rigid3d mic_from_map = map_from_mic.inverse();
  int associated = 0;
  for (const auto& d : detections) {
    const double sigma_det = std::max(d.azimuth_sigma_rad, options_.min_direction_sigma_rad);
    const SoundSource* best = nullptr;
    double best_score = options_.heard_gate_chi2;
    int in_gate = 0;  // sources this direction could be pointing at
    for (const auto& entry : sources_) {
      const SoundSource& s = entry.second;
      const Eigen::Vector3d v = mic_from_map * s.position_m;
      const double range = v.head<2>().norm();
      if (range < 1e-3) continue;
      const double error = common::WrapAngle(d.azimuth_rad - std::atan2(v.y(), v.x()));
      // Source uncertainty across the bearing, as an angle.
      const Eigen::Vector3d across_map =
          map_from_mic.rotation() * Eigen::Vector3d(-v.y(), v.x(), 0.0).normalized();
      const double var_across = across_map.dot(s.covariance * across_map);
      // A source known only to tens of degrees (just born, or with a range of kilometres) lies in
      // every direction's gate: it would take every call and, counted in in_gate, block the
      // source the caller really is (a people map restarted after such a source appeared then
      // never placed the caller). It neither names nor blocks.
      constexpr double kMaxSourceAngleSigmaRad = 0.5;
      if (var_across > std::pow(kMaxSourceAngleSigmaRad * range, 2)) continue;
      const double variance = sigma_det * sigma_det + var_across / (range * range);
      const double score = error * error / variance;
      if (score <= options_.heard_gate_chi2) ++in_gate;
      if (score <= best_score) {
        best_score = score;
        best = &s;
      }
    }
    (void)origin;
    if (!best) continue;
    ++associated;
    // The person this source is, found or made.
    Person* p = nullptr;
    for (auto& [id, q] : people_) {
      if (q.sound_source_id == best->id) p = &q;
    }
    if (!p && source_alias_.count(best->id)) {
      auto alias = people_.find(source_alias_[best->id]);
      if (alias != people_.end()) {
        // A call towards a merged duplicate source is evidence for the caller it was merged into.
        source_heard_utime_[best->id] = utime;
        AddEvidence(&alias->second, utime, d.confidence);
        continue;
      }
    }
    // A direction through two sound sources (one behind the other, as along a corridor) does not
    // say which of them called: it makes no one a person.
    if (!p && in_gate > 1) continue;
    source_heard_utime_[best->id] = utime;
    if (!d.keyword.empty()) source_keyword_[best->id] = d.keyword;
    auto& calls = source_call_utimes_[best->id];
    calls.erase(std::remove_if(calls.begin(), calls.end(),
                               [&](Utime t) {
                                 return common::UtimeToSeconds(utime - t) >
                                        options_.heard_person_window_s;
                               }),
                calls.end());
    // Several keywords of one utterance are one call.
    if (calls.empty() ||
        std::abs(common::UtimeToSeconds(utime - calls.back())) >= options_.same_call_s)
      calls.push_back(utime);
    // Not yet placed: one call may be a keyword false alarm, and an initialising source's
    // position is a guess; UpdateSoundSources places the person once both are settled.
    if (!p && RecentCalls(best->id, utime) < options_.min_heard_calls) continue;
    if (!p && !Placed(*best)) continue;
    if (!p) {
      for (auto& [id, q] : people_) {
        if (q.has_heard || !q.has_seen) continue;
        if (HeardAgreesWithSeen(q.seen_position_m, q.seen_covariance, best->position_m,
                                best->covariance)) {
          p = &q;
          break;
        }
      }
    }
    // Only voices become people: a keyword false alarm on a machine or an alarm makes nobody
    // (the call is counted; the source becomes a person if the sound map later calls it a voice).
    if (!p && !best->is_person) continue;
    if (!p) p = NewPerson(utime);
    p->sound_source_id = best->id;
    p->has_heard = true;
    p->heard_position_m = best->position_m;
    p->heard_covariance = best->covariance;
    p->cues |= kHeard;
    if (!d.keyword.empty()) p->keyword = d.keyword;
    AddEvidence(p, utime, d.confidence);
    Refuse(p);
  }
  return associated;
}

void PeopleMap::UpdateSoundSources(Utime utime, const std::vector<SoundSource>& sources) {
  sources_.clear();
  for (const auto& s : sources) {
    // A source without a finite position and covariance is garbage, never a place for a person.
    if (!s.position_m.allFinite() || !s.covariance.allFinite()) continue;
    sources_[s.id] = s;
  }
  for (const auto& entry : sources_) {
    const SoundSource& s = entry.second;
    const auto heard = source_heard_utime_.find(s.id);
    const bool recently_heard =
        heard != source_heard_utime_.end() &&
        common::UtimeToSeconds(utime - heard->second) <= options_.heard_person_window_s;
    Person* linked = nullptr;
    for (auto& [id, q] : people_) {
      if (q.sound_source_id == s.id) linked = &q;
    }
    if (!linked && source_alias_.count(s.id) && people_.count(source_alias_[s.id]))
      continue;  // merged duplicate
    if (linked) {
      // The sound map refines the position as the robot moves.
      linked->heard_position_m = s.position_m;
      linked->heard_covariance = s.covariance;
      Refuse(linked);
    } else if (s.is_person && recently_heard && Placed(s) &&
               RecentCalls(s.id, utime) >= options_.min_heard_calls) {
      Person& p = *NewPerson(utime);
      p.sound_source_id = s.id;
      p.has_heard = true;
      p.heard_position_m = s.position_m;
      p.heard_covariance = s.covariance;
      p.cues = kHeard;
      if (source_keyword_.count(s.id)) p.keyword = source_keyword_[s.id];
      AddEvidence(&p, utime, 0.8);
      Refuse(&p);
    }
  }
  // A heard-only person that now agrees with a seen-only one: one person, both cues.
  for (auto h = people_.begin(); h != people_.end();) {
    Person& heard = h->second;
    bool merged = false;
    if (heard.has_heard && !heard.has_seen) {
      for (auto& [id, seen] : people_) {
        if (!seen.has_seen || seen.has_heard) continue;
        if (HeardAgreesWithSeen(seen.seen_position_m, seen.seen_covariance, heard.heard_position_m,
                                heard.heard_covariance)) {
          seen.has_heard = true;
          seen.heard_position_m = heard.heard_position_m;
          seen.heard_covariance = heard.heard_covariance;
          seen.sound_source_id = heard.sound_source_id;
          seen.cues |= heard.cues;
          if (!heard.keyword.empty()) seen.keyword = heard.keyword;
          AddDetectionsOf(heard, &seen);
          Refuse(&seen);
          merged = true;
          break;
        }
      }
    }
    // A heard-only person within merge_radius_m of another heard person is the same caller: the
    // sound map split one voice into two sources (its bearings from two stretches of the path).
    if (!merged && heard.has_heard && !heard.has_seen) {
      for (auto& [id, other] : people_) {
        if (id == heard.id || !other.has_heard || (!other.has_seen && id > heard.id)) continue;
        // ... or a seen person who agrees with it as a heard-only person agrees with a seen one.
        const bool close =
            (other.position_m - heard.heard_position_m).head<2>().norm() <= options_.merge_radius_m;
        const bool agrees_with_seen =
            other.has_seen && HeardAgreesWithSeen(other.seen_position_m, other.seen_covariance,
                                                  heard.heard_position_m, heard.heard_covariance);
        if (!close && !agrees_with_seen) continue;
        source_alias_[heard.sound_source_id] = id;
        AddDetectionsOf(heard, &other);
        merged = true;
        break;
      }
    }
    h = merged ? people_.erase(h) : std::next(h);
  }
}

std::vector<Person> PeopleMap::Report(Utime utime) const {
  std::vector<Person> out;
  for (const auto& [id, p] : people_) {
    if (!Reported(p, utime)) continue;
    Person copy = p;
    copy.confidence = DecayedConfidence(p, utime);
    out.push_back(copy);
  }
  return out;
}

void PeopleMap::Save(const std::string& path) const {
  YAML::Node root;
  root["version"] = kStateVersion;
  root["next_id"] = next_id_;
  for (const auto& [id, p] : people_) {
    YAML::Node n;
    n["id"] = p.id;
    n["position_m"] = Vec(p.position_m);
    n["covariance"] = Mat(p.covariance);
    n["confidence"] = p.confidence;
    n["confirmed"] = p.confirmed;
    n["cues"] = static_cast<int>(p.cues);
    n["num_detections"] = p.num_detections;
    n["people_count"] = p.people_count;
    n["first_detected_utime"] = p.first_detected_utime;
    n["last_detected_utime"] = p.last_detected_utime;
    n["keyword"] = p.keyword;
    n["sound_source_id"] = p.sound_source_id;
    n["has_seen"] = p.has_seen;
    n["seen_position_m"] = Vec(p.seen_position_m);
    n["seen_covariance"] = Mat(p.seen_covariance);
    n["has_heard"] = p.has_heard;
    n["heard_position_m"] = Vec(p.heard_position_m);
    n["heard_covariance"] = Mat(p.heard_covariance);
    n["anchor_node_id"] = p.anchor_node_id;
    YAML::Node anchor;
    anchor.push_back(p.map_from_anchor_node.translation().x());
    anchor.push_back(p.map_from_anchor_node.translation().y());
    anchor.push_back(p.map_from_anchor_node.yaw_rad());
    anchor.SetStyle(YAML::EmitterStyle::Flow);
    n["map_from_anchor_node"] = anchor;
    root["people"].push_back(n);
  }
  for (const auto& [id, t] : source_heard_utime_) {
    YAML::Node n;
    n["source_id"] = id;
    n["heard_utime"] = t;
    n["keyword"] = source_keyword_.count(id) ? source_keyword_.at(id) : "";
    // The calls that count towards min_heard_calls: a restart that forgot them would need two
    // more calls, and a hidden caller is heard only now and then.
    const auto calls = source_call_utimes_.find(id);
    n["call_utimes"] = YAML::Node(YAML::NodeType::Sequence);
    if (calls != source_call_utimes_.end())
      for (Utime c : calls->second) n["call_utimes"].push_back(c);
    root["heard_sources"].push_back(n);
  }
  // Sound sources merged into a caller as duplicates: a restart that forgot them would make the
  // duplicate a person again at its next calls.
  for (const auto& [source_id, person_id] : source_alias_) {
    YAML::Node n;
    n["source_id"] = source_id;
    n["person_id"] = person_id;
    root["source_aliases"].push_back(n);
  }
  YAML::Emitter out;
  out << root;
  common::WriteSealedState(path, kStateKind, kStateVersion, std::string(out.c_str()) + "\n");
}

bool PeopleMap::Load(const std::string& path) {
  std::string text;
  // Throws StateFileError (another kind or version, truncated, checksum) before any parsing.
  const common::StateFileRead read =
      common::ReadSealedState(path, kStateKind, kStateVersion, &text);
  if (read == common::StateFileRead::kMissing) return false;
  YAML::Node root;
  try {
    root = YAML::Load(text);
    // Files written before sealing are version 1 with the same fields.
    const int version = root["version"] ? root["version"].as<int>() : -1;
    if (read == common::StateFileRead::kUnsealed ? version != 1 : version != kStateVersion) {
      throw std::runtime_error("version " + std::to_string(version));
    }
    std::map<int64_t, Person> people;
    for (const auto& n : root["people"]) {
      Person p;
      p.id = n["id"].as<int64_t>();
      p.position_m = ToVec(n["position_m"]);
      p.covariance = ToMat(n["covariance"]);
      p.confidence = n["confidence"].as<double>();
      p.confirmed = n["confirmed"] && n["confirmed"].as<bool>();  // a file without it: false
      p.cues = static_cast<uint8_t>(n["cues"].as<int>());
      p.num_detections = n["num_detections"].as<int>();
      p.people_count = n["people_count"].as<int>();
      p.first_detected_utime = n["first_detected_utime"].as<int64_t>();
      p.last_detected_utime = n["last_detected_utime"].as<int64_t>();
      p.keyword = n["keyword"].as<std::string>();
      p.sound_source_id = n["sound_source_id"].as<int64_t>();
      p.has_seen = n["has_seen"].as<bool>();
      p.seen_position_m = ToVec(n["seen_position_m"]);
      p.seen_covariance = ToMat(n["seen_covariance"]);
      p.has_heard = n["has_heard"].as<bool>();
      p.heard_position_m = ToVec(n["heard_position_m"]);
      p.heard_covariance = ToMat(n["heard_covariance"]);
      if (n["anchor_node_id"]) {  // optional: older state files lack it (no anchor)
        const Eigen::Vector3d a = ToVec(n["map_from_anchor_node"]);
        if (!a.allFinite()) throw std::runtime_error("non-finite anchor node pose");
        p.anchor_node_id = n["anchor_node_id"].as<int64_t>();
        p.map_from_anchor_node = common::Rigid2d(a.x(), a.y(), a.z());
      }
      // The sightings so far are settled: a restart ends the current one.
      p.has_settled = p.has_seen;
      p.settled_position_m = p.seen_position_m;
      p.settled_covariance = p.seen_covariance;
      // A NaN or infinite value would spread to every person it is fused with.
      if (!p.position_m.allFinite() || !p.covariance.allFinite() || !std::isfinite(p.confidence) ||
          !p.seen_position_m.allFinite() || !p.seen_covariance.allFinite() ||
          !p.heard_position_m.allFinite() || !p.heard_covariance.allFinite()) {
        throw std::runtime_error("person " + std::to_string(p.id) + " has a non-finite value");
      }
      people[p.id] = p;
    }
    std::map<int64_t, Utime> heard;
    std::map<int64_t, std::string> keywords;
    std::map<int64_t, std::vector<Utime>> calls;
    for (const auto& n : root["heard_sources"]) {
      const int64_t id = n["source_id"].as<int64_t>();
      heard[id] = n["heard_utime"].as<int64_t>();
      keywords[id] = n["keyword"].as<std::string>();
      if (n["call_utimes"])  // optional: older state files lack it
        for (const auto& c : n["call_utimes"]) calls[id].push_back(c.as<int64_t>());
    }
    std::map<int64_t, int64_t> aliases;
    for (const auto& n : root["source_aliases"])  // optional: older state files lack it
      aliases[n["source_id"].as<int64_t>()] = n["person_id"].as<int64_t>();
    next_id_ = root["next_id"].as<int64_t>();
    people_ = std::move(people);
    source_alias_ = std::move(aliases);
    source_heard_utime_ = std::move(heard);
    source_keyword_ = std::move(keywords);
    source_call_utimes_ = std::move(calls);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": corrupt people-map state (" + e.what() + ")");
  }
  return true;
}

}  // namespace people_map
}  // namespace sarmap
