#include "sound_localisation/array_geometry.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sarmap {
namespace sound {

double DegToRad(double d) { return d * M_PI / 180.0; }
double RadToDeg(double r) { return r * 180.0 / M_PI; }

ArrayGeometry ArrayGeometry::FromOptions(const common::MicArrayOptions& options) {
  ArrayGeometry g;
  g.name = options.name;
  g.geometry = options.geometry;
  g.speed_of_sound_mps = options.speed_of_sound_mps;
  g.sample_rate_hz = options.sample_rate_hz;
  const int n = options.num_mics();
  if (n < 2) throw std::invalid_argument("array '" + options.name + "' needs at least 2 microphones");
  g.positions_m.resize(3, n);
  for (int i = 0; i < n; ++i) g.positions_m.col(i) = options.mic_position(i);
  g.channel_map = options.channel_map;
  if (g.channel_map.empty())
    for (int i = 0; i < n; ++i) g.channel_map.push_back(i);
  // Principal axes of the microphone cloud.
  const Eigen::Vector3d centre = g.positions_m.rowwise().mean();
  const Eigen::Matrix3Xd centred = g.positions_m.colwise() - centre;
  Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(centred, Eigen::ComputeFullU);
  const Eigen::Vector3d sv = svd.singularValues();
  const double scale = std::max(sv(0), 1e-9);
  if (g.is_linear()) {
    if (sv(1) > 1e-3 * scale * 10)
      throw std::invalid_argument("array '" + options.name +
                                  "': geometry is linear but the microphones are not on a line");
    g.axis = (g.positions_m.col(n - 1) - g.positions_m.col(0)).normalized();
  } else {
    g.normal = svd.matrixU().col(2);
    if (g.normal.z() < 0) g.normal = -g.normal;
    if (g.geometry == "planar" && sv(2) > 0.2 * scale)
      throw std::invalid_argument("array '" + options.name + "': geometry is planar but microphones are not");
  }
  return g;
}

double ArrayGeometry::aperture_m() const {
  double best = 0;
  for (int i = 0; i < num_mics(); ++i)
    for (int j = i + 1; j < num_mics(); ++j)
      best = std::max(best, (positions_m.col(i) - positions_m.col(j)).norm());
  return best;
}

void ArrayGeometry::CheckChannels(int block_channels) const {
  for (int c : channel_map)
    if (c >= block_channels)
      throw std::invalid_argument("array '" + name + "' uses device channel " + std::to_string(c) +
                                  " but the audio has " + std::to_string(block_channels) +
                                  " channels");
}

double ArrayGeometry::UniformSpacing() const {
  if (!is_linear() || num_mics() < 3) return is_linear() ? aperture_m() : 0;
  const double d = (positions_m.col(1) - positions_m.col(0)).norm();
  for (int i = 1; i + 1 < num_mics(); ++i) {
    const double di = (positions_m.col(i + 1) - positions_m.col(i)).norm();
    if (std::abs(di - d) > 0.02 * d) return 0;
    if ((positions_m.col(i + 1) - positions_m.col(i)).dot(axis) <= 0) return 0;
  }
  return d;
}

Eigen::Vector3d ArrayGeometry::Unit(DoaKind kind, const Direction& d) const {
  if (kind == DoaKind::kAngle1d) {
    // Any vector on the cone; pick the one in the plane of the axis and a fixed perpendicular.
    Eigen::Vector3d perp = axis.unitOrthogonal();
    return std::cos(d.azimuth_rad) * axis + std::sin(d.azimuth_rad) * perp;
  }
  const double el = kind == DoaKind::kAzimuth ? 0.0 : d.elevation_rad;
  return Eigen::Vector3d(std::cos(el) * std::cos(d.azimuth_rad), std::cos(el) * std::sin(d.azimuth_rad),
                         std::sin(el));
}

Direction ArrayGeometry::FromUnit(DoaKind kind, const Eigen::Vector3d& u) const {
  Direction d;
  if (kind == DoaKind::kAngle1d) {
    d.azimuth_rad = std::acos(std::clamp(u.normalized().dot(axis), -1.0, 1.0));
    return d;
  }
  d.azimuth_rad = std::atan2(u.y(), u.x());
  if (kind == DoaKind::kAzimuthElevation)
    d.elevation_rad = std::atan2(u.z(), std::hypot(u.x(), u.y()));
  return d;
}

double AngularDistanceRad(const ArrayGeometry& g, DoaKind kind, const Direction& a, const Direction& b) {
  if (kind == DoaKind::kAngle1d) return std::abs(a.azimuth_rad - b.azimuth_rad);
  if (kind == DoaKind::kAzimuth) return std::abs(WrapAngle(a.azimuth_rad - b.azimuth_rad));
  const double c = g.Unit(kind, a).dot(g.Unit(kind, b));
  return std::acos(std::clamp(c, -1.0, 1.0));
}

}  // namespace sound
}  // namespace sarmap
