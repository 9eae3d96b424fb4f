#include "sound_localisation/tracker.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace sarmap {
namespace sound {

DoaTracker::DoaTracker(const ArrayGeometry& geometry, DoaKind kind, TrackerOptions options)
    : geometry_(geometry), kind_(kind), options_(options) {}

std::vector<Track> DoaTracker::Update(double time_s,
                                      const std::vector<TrackMeasurement>& measurements) {
  const double dt = last_time_s_ < 0 ? 0.0 : std::max(0.0, time_s - last_time_s_);
  last_time_s_ = time_s;
  const double q = DegToRad(options_.process_noise_deg_per_sqrt_s);
  const double qv = DegToRad(options_.velocity_noise_deg_per_s_sqrt_s);
  const bool cv = qv > 0;
  // Rate as an Ornstein-Uhlenbeck process: v' = -v / T + noise; position integrates it.
  const double decay = std::exp(-dt / options_.velocity_time_constant_s);
  const double integral = options_.velocity_time_constant_s * (1 - decay);  // int_0^dt decay(s) ds
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F(0, 2) = F(1, 3) = integral;
  F(2, 2) = F(3, 3) = decay;
  // Kinds with one angle (1-D, azimuth only) observe the first angle alone: the second keeps
  // the variance it was born with (the measurement's "unknown") and takes neither process
  // noise nor a gain, so its variance never grows without bound or turns negative.
  const bool two_angles = kind_ == DoaKind::kAzimuthElevation;
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
  Q(0, 0) = q * q * dt + qv * qv * dt * dt * dt / 3;
  Q(0, 2) = Q(2, 0) = qv * qv * dt * dt / 2;
  Q(2, 2) = qv * qv * dt;
  if (two_angles) {
    Q(1, 1) = Q(0, 0);
    Q(1, 3) = Q(3, 1) = Q(0, 2);
    Q(3, 3) = Q(2, 2);
  }
  for (Track& t : tracks_) {
    if (cv) {
      t.direction.azimuth_rad += integral * t.rate(0);
      t.direction.elevation_rad += integral * t.rate(1);
      t.rate *= decay;
      t.state_covariance = F * t.state_covariance * F.transpose() + Q;
      if (!two_angles) t.state_covariance(1, 1) = t.covariance(1, 1);
      t.covariance = t.state_covariance.topLeftCorner<2, 2>();
    } else {
      t.covariance(0, 0) += q * q * dt;
      if (two_angles) t.covariance(1, 1) += q * q * dt;
    }
    t.updated = false;
  }
  auto innovation_of = [&](const Track& t, const TrackMeasurement& m) {
    Eigen::Vector2d v(m.direction.azimuth_rad - t.direction.azimuth_rad,
                      m.direction.elevation_rad - t.direction.elevation_rad);
    if (kind_ != DoaKind::kAngle1d) v(0) = WrapAngle(v(0));
    if (kind_ != DoaKind::kAzimuthElevation) v(1) = 0;
    return v;
  };
  auto innovation_covariance = [&](const Track& t, const TrackMeasurement& m) {
    Eigen::Matrix2d S = t.covariance + m.covariance;
    if (kind_ != DoaKind::kAzimuthElevation) {
      S(0, 1) = S(1, 0) = 0;
      S(1, 1) = 1;
    }
    return S;
  };
  // chi2 quantile with 2 degrees of freedom (1 for 1-D kinds).
  const int dof = kind_ == DoaKind::kAzimuthElevation ? 2 : 1;
  double gate_d2 = INFINITY;
  if (options_.gate_probability > 0) {
    const double p = options_.gate_probability;
    if (dof == 2) {
      gate_d2 = -2 * std::log(1 - p);
    } else {
      double lo = 0, hi = 100;  // P(|N| < sqrt(d2)) = erf(sqrt(d2 / 2))
      for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (std::erf(std::sqrt(mid / 2)) < p ? lo : hi) = mid;
      }
      gate_d2 = hi;
    }
  }
  // Greedy association, smallest Mahalanobis distance first.
  struct Pair {
    double distance;
    size_t track, meas;
  };
  std::vector<Pair> pairs;
  const double gate = DegToRad(options_.gate_deg);
  for (size_t i = 0; i < tracks_.size(); ++i)
    for (size_t j = 0; j < measurements.size(); ++j) {
      const double d =
          AngularDistanceRad(geometry_, kind_, tracks_[i].direction, measurements[j].direction);
      if (d >= gate) continue;
      const Eigen::Vector2d v = innovation_of(tracks_[i], measurements[j]);
      const double d2 = v.dot(innovation_covariance(tracks_[i], measurements[j]).ldlt().solve(v));
      if (d2 < gate_d2) pairs.push_back({d2, i, j});
    }
  std::sort(pairs.begin(), pairs.end(),
            [](const Pair& a, const Pair& b) { return a.distance < b.distance; });
  std::vector<bool> track_used(tracks_.size(), false), meas_used(measurements.size(), false);
  for (const Pair& p : pairs) {
    if (track_used[p.track] || meas_used[p.meas]) continue;
    track_used[p.track] = meas_used[p.meas] = true;
    Track& t = tracks_[p.track];
    const TrackMeasurement& m = measurements[p.meas];
    const Eigen::Vector2d innovation = innovation_of(t, m);
    const Eigen::Matrix2d S = innovation_covariance(t, m);
    if (!two_angles) {
      // The first angle alone is observed: H = e0^T, a scalar innovation.
      const double s0 = (cv ? t.state_covariance(0, 0) : t.covariance(0, 0)) + m.covariance(0, 0);
      if (cv) {
        const Eigen::Vector4d k = t.state_covariance.col(0) / s0;
        t.direction.azimuth_rad += k(0) * innovation(0);
        t.rate(0) += k(2) * innovation(0);
        t.rate(1) = 0;
        const Eigen::Matrix4d reduced = k * t.state_covariance.row(0);
        t.state_covariance -= reduced;
        t.covariance(0, 0) = t.state_covariance(0, 0);
      } else {
        const double k = t.covariance(0, 0) / s0;
        t.direction.azimuth_rad += k * innovation(0);
        t.covariance(0, 0) *= 1 - k;
      }
    } else if (cv) {
      // H = [I 0]: K = P H^T S^-1.
      const Eigen::Matrix<double, 4, 2> K = t.state_covariance.leftCols<2>() * S.inverse();
      Eigen::Vector2d innov = innovation;
      const Eigen::Vector4d dx = K * innov;
      t.direction.azimuth_rad += dx(0);
      t.direction.elevation_rad += dx(1);
      t.rate += dx.tail<2>();
      Eigen::Matrix<double, 2, 4> H = Eigen::Matrix<double, 2, 4>::Zero();
      H(0, 0) = H(1, 1) = 1;
      t.state_covariance = (Eigen::Matrix4d::Identity() - K * H) * t.state_covariance;
      t.covariance = t.state_covariance.topLeftCorner<2, 2>();
    } else {
      const Eigen::Matrix2d K = t.covariance * S.inverse();
      const Eigen::Vector2d dx = K * innovation;
      t.direction.azimuth_rad += dx(0);
      t.direction.elevation_rad += dx(1);
      t.covariance = (Eigen::Matrix2d::Identity() - K) * t.covariance;
    }
    if (kind_ == DoaKind::kAngle1d)
      t.direction.azimuth_rad = std::clamp(t.direction.azimuth_rad, 0.0, M_PI);
    else
      t.direction.azimuth_rad = WrapAngle(t.direction.azimuth_rad);
    t.last_update_s = time_s;
    ++t.hits;
    t.primary_hits += m.primary;
    t.updated = true;
    t.power = m.power;
    t.confidence = m.confidence;
    if (!t.confirmed() && t.hits >= options_.birth_hits && t.primary_hits >= options_.primary_hits)
      t.id = next_id_++;
  }
  // Births.
  for (size_t j = 0; j < measurements.size(); ++j) {
    if (meas_used[j]) continue;
    Track t;
    t.direction = measurements[j].direction;
    t.covariance = measurements[j].covariance;
    t.state_covariance.topLeftCorner<2, 2>() = t.covariance;
    // A newborn's rate is unknown: up to a fast walker's bearing rate (~ 1 rad/s).
    t.state_covariance(2, 2) = t.state_covariance(3, 3) = cv ? 1.0 : 0.0;
    t.birth_s = t.last_update_s = time_s;
    t.hits = 1;
    t.primary_hits = measurements[j].primary;
    t.updated = true;
    t.power = measurements[j].power;
    t.confidence = measurements[j].confidence;
    if (options_.birth_hits <= 1 && t.primary_hits >= options_.primary_hits) t.id = next_id_++;
    tracks_.push_back(t);
  }
  // Deaths.
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& t) {
                                 if (!t.confirmed())
                                   return time_s - t.birth_s > options_.birth_window_s;
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
