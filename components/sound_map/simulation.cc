#include "sound_map/simulation.h"

#include <cmath>
#include <random>

namespace sarmap {
namespace sound_map {

Eigen::Matrix3d Sim2dData::odometry_covariance() const {
  return Eigen::Vector3d(config.odo_sigma_m * config.odo_sigma_m, config.odo_sigma_m * config.odo_sigma_m,
                         config.odo_sigma_rad * config.odo_sigma_rad)
      .asDiagonal();
}

double Sim2dData::length_m() const { return config.step_m * static_cast<double>(odometry.size() - 1); }

Sim2dConfig Fig411Config(double side_m, int run) {
  Sim2dConfig c;
  c.side_m = side_m;
  c.overshoot_m = 5.0;
  c.landmarks = true;
  c.odo_sigma_m = 0.02;
  c.odo_sigma_rad = 5.0 * M_PI / 180;
  c.seed = 2000 + run;
  return c;
}

Sim2dData Simulate2d(const Sim2dConfig& c) {
  Sim2dData d;
  d.config = c;
  std::mt19937_64 rng(c.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);

  // Path: the square (left turns at the corners) then the overshoot along +x.
  const int steps_per_side = static_cast<int>(std::lround(c.side_m / c.step_m));
  const int overshoot_steps = static_cast<int>(std::lround(c.overshoot_m / c.step_m));
  std::vector<Pose2> truth = {Pose2(0, 0, 0)};
  std::vector<Pose2> increments = {Pose2()};
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < steps_per_side; ++k) {
      const bool corner = (k == steps_per_side - 1) && side < 4;
      const Pose2 u(c.step_m, 0.0, corner ? M_PI / 2 : 0.0);
      truth.push_back(Compose(truth.back(), u));
      increments.push_back(u);
    }
  }
  for (int k = 0; k < overshoot_steps; ++k) {
    const Pose2 u(c.step_m, 0.0, 0.0);
    truth.push_back(Compose(truth.back(), u));
    increments.push_back(u);
  }
  d.truth = truth;
  d.odometry.resize(truth.size());
  for (size_t k = 1; k < truth.size(); ++k) {
    const Pose2& u = increments[k];
    d.odometry[k] = Pose2(u.x + c.odo_sigma_m * n01(rng), u.y + c.odo_sigma_m * n01(rng),
                          WrapAngle(u.yaw + c.odo_sigma_rad * n01(rng)));
  }

  // Sources: one per source_spacing_m of the square's perimeter, alternately outside and
  // inside the square; in 3D alternately 1 m above and below the array.
  const double perimeter = 4.0 * c.side_m;
  const int num_sources = std::max(1, static_cast<int>(std::floor(perimeter / c.source_spacing_m)));
  for (int i = 0; i < num_sources; ++i) {
    const double s = (i + 0.5) * perimeter / num_sources;
    const int side = std::min(3, static_cast<int>(s / c.side_m));
    const double along = s - side * c.side_m;
    const double off = (i % 2 == 0 ? -1.0 : 1.0) * c.source_offset_m;  // - outside, + inside
    Eigen::Vector2d p, dir, left;
    switch (side) {
      case 0: p = {along, 0}; dir = {1, 0}; break;
      case 1: p = {c.side_m, along}; dir = {0, 1}; break;
      case 2: p = {c.side_m - along, c.side_m}; dir = {-1, 0}; break;
      default: p = {0, c.side_m - along}; dir = {0, -1}; break;
    }
    left = Eigen::Vector2d(-dir.y(), dir.x());
    const Eigen::Vector2d xy = p + off * left;
    const double z = c.three_d ? ((i / 2) % 2 == 0 ? 1.0 : -1.0) : 0.0;
    d.sources.emplace_back(xy.x(), xy.y(), z);
  }
  if (c.landmarks) {
    const int n = static_cast<int>(std::floor(perimeter / c.landmark_spacing_m));
    for (int i = 0; i < n; ++i) {
      const double s = (i + 0.25) * c.landmark_spacing_m;
      const int side = std::min(3, static_cast<int>(s / c.side_m));
      const double along = s - side * c.side_m;
      Eigen::Vector2d p, dir;
      switch (side) {
        case 0: p = {along, 0}; dir = {1, 0}; break;
        case 1: p = {c.side_m, along}; dir = {0, 1}; break;
        case 2: p = {c.side_m - along, c.side_m}; dir = {-1, 0}; break;
        default: p = {0, c.side_m - along}; dir = {0, -1}; break;
      }
      const Eigen::Vector2d left(-dir.y(), dir.x());
      d.landmarks.push_back(p + c.landmark_offset_m * left);
      d.landmarks.push_back(p - c.landmark_offset_m * left);
    }
  }

  d.landmark_obs.resize(truth.size());
  d.sound_obs.resize(truth.size());
  for (size_t k = 0; k < truth.size(); ++k) {
    const double pose[3] = {truth[k].x, truth[k].y, truth[k].yaw};
    for (size_t j = 0; j < d.landmarks.size(); ++j) {
      double z[2];
      RangeBearing(pose, d.landmarks[j].data(), z);
      if (z[0] > c.landmark_range_m) continue;
      d.landmark_obs[k].push_back({static_cast<int64_t>(j),
                                   Eigen::Vector2d(z[0] + c.landmark_sigma_m * n01(rng),
                                                   WrapAngle(z[1] + c.landmark_sigma_rad * n01(rng)))});
    }
    for (size_t j = 0; j < d.sources.size(); ++j) {
      const Eigen::Vector3d& p = d.sources[j];
      if (std::hypot(p.x() - pose[0], p.y() - pose[1]) > c.hearing_range_m) continue;
      if (u01(rng) > c.heard_probability) continue;
      double z[2];
      PointObservation(pose, p.data(), c.three_d, d.mount, z);
      Eigen::VectorXd zn(c.three_d ? 2 : 1);
      zn[0] = WrapAngle(z[0] + c.sound_sigma_rad * n01(rng));
      if (c.three_d) zn[1] = z[1] + c.sound_sigma_rad * n01(rng);
      d.sound_obs[k].push_back({static_cast<int64_t>(j), zn});
    }
  }
  return d;
}

}  // namespace sound_map
}  // namespace sarmap
