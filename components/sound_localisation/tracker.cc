#include "sound_localisation/tracker.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace sarmap {
namespace sound {

DoaTracker::DoaTracker(const ArrayGeometry& geometry, DoaKind kind, TrackerOptions options)
    : geometry_(geometry), kind_(kind), options_(options) {}

std::vector<Track> DoaTracker::Update(double time_s, const std::vector<TrackMeasurement>& measurements) {
  const double dt = last_time_s_ < 0 ? 0.0 : std::max(0.0, time_s - last_time_s_);
  last_time_s_ = time_s;
  const double q = DegToRad(options_.process_noise_deg_per_sqrt_s);
  for (Track& t : tracks_) {
    t.covariance.diagonal().array() += q * q * dt;
    t.updated = false;
  }
  // Greedy association, closest pairs first.
  struct Pair {
    double distance;
    size_t track, meas;
  };
  std::vector<Pair> pairs;
  const double gate = DegToRad(options_.gate_deg);
  for (size_t i = 0; i < tracks_.size(); ++i)
    for (size_t j = 0; j < measurements.size(); ++j) {
      const double d = AngularDistanceRad(geometry_, kind_, tracks_[i].direction, measurements[j].direction);
      if (d < gate) pairs.push_back({d, i, j});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.distance < b.distance;
  });
  std::vector<bool> track_used(tracks_.size(), false), meas_used(measurements.size(), false);
  for (const Pair& p : pairs) {
    if (track_used[p.track] || meas_used[p.meas]) continue;
    track_used[p.track] = meas_used[p.meas] = true;
    Track& t = tracks_[p.track];
    const TrackMeasurement& m = measurements[p.meas];
    Eigen::Vector2d innovation(m.direction.azimuth_rad - t.direction.azimuth_rad,
                               m.direction.elevation_rad - t.direction.elevation_rad);
    if (kind_ != DoaKind::kAngle1d) innovation(0) = WrapAngle(innovation(0));
    if (kind_ != DoaKind::kAzimuthElevation) innovation(1) = 0;
    Eigen::Matrix2d S = t.covariance + m.covariance;
    const Eigen::Matrix2d K = t.covariance * S.inverse();
    const Eigen::Vector2d dx = K * innovation;
    t.direction.azimuth_rad += dx(0);
    t.direction.elevation_rad += dx(1);
    if (kind_ == DoaKind::kAngle1d) t.direction.azimuth_rad = std::clamp(t.direction.azimuth_rad, 0.0, M_PI);
    else t.direction.azimuth_rad = WrapAngle(t.direction.azimuth_rad);
    t.covariance = (Eigen::Matrix2d::Identity() - K) * t.covariance;
    t.last_update_s = time_s;
    ++t.hits;
    t.updated = true;
    t.power = m.power;
    t.confidence = m.confidence;
    if (!t.confirmed() && t.hits >= options_.birth_hits) t.id = next_id_++;
  }
  // Births.
  for (size_t j = 0; j < measurements.size(); ++j) {
    if (meas_used[j]) continue;
    Track t;
    t.direction = measurements[j].direction;
    t.covariance = measurements[j].covariance;
    t.birth_s = t.last_update_s = time_s;
    t.hits = 1;
    t.updated = true;
    t.power = measurements[j].power;
    t.confidence = measurements[j].confidence;
    if (options_.birth_hits <= 1) t.id = next_id_++;
    tracks_.push_back(t);
  }
  // Deaths.
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& t) {
                                 if (!t.confirmed()) return time_s - t.birth_s > options_.birth_window_s;
                                 return time_s - t.last_update_s > options_.max_silence_s;
                               }),
                tracks_.end());
  std::vector<Track> out;
  for (const Track& t : tracks_)
    if (t.confirmed()) out.push_back(t);
  std::sort(out.begin(), out.end(), [](const Track& a, const Track& b) { return a.id < b.id; });
  return out;
}

}  // namespace sound
}  // namespace sarmap
