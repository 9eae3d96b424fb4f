#pragma once
// Microphone-array geometry and directions in the mic_array frame.
//
// A direction is a unit vector u pointing from the array origin to a far-field source:
//   u = (cos(el) cos(az), cos(el) sin(az), sin(el)).
// A plane wave from u reaches microphone m (position p_m) earlier than the origin by
// p_m . u / c, so its relative delay is tau_m(u) = -p_m . u / c and its steering vector at
// angular frequency w is a_m = exp(-j w tau_m).
// Linear arrays only see the angle theta between u and the array axis (0..pi, a cone);
// for them Direction::azimuth_rad holds theta (doa_source_t KIND_ANGLE_1D).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/angles.h"
#include "common/robot_config.h"

namespace sarmap {
namespace sound {

enum class DoaKind { kAngle1d = 1, kAzimuth = 2, kAzimuthElevation = 3 };

struct Direction {
  double azimuth_rad = 0;    // or angle to the axis for kAngle1d
  double elevation_rad = 0;
};

struct ArrayGeometry {
  std::string name;
  std::string geometry;              // linear | planar | 3d
  Eigen::Matrix3Xd positions_m;      // one column per microphone
  std::vector<int> channel_map;      // device channel of each microphone
  double speed_of_sound_mps = 343.0;
  int sample_rate_hz = 16000;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // linear arrays: unit axis (first -> last)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // planar arrays: plane normal

  // Throws std::invalid_argument when the description is inconsistent (e.g. a "linear"
  // array whose microphones are not on a line).
  static ArrayGeometry FromOptions(const common::MicArrayOptions& options);
  int num_mics() const { return static_cast<int>(positions_m.cols()); }
  double aperture_m() const;  // largest microphone distance
  bool is_linear() const { return geometry == "linear"; }
  // Default search for this geometry: 1-D for linear, azimuth+elevation otherwise.
  DoaKind natural_kind() const { return is_linear() ? DoaKind::kAngle1d : DoaKind::kAzimuthElevation; }
  // Unit vector of a direction of the given kind.
  Eigen::Vector3d Unit(DoaKind kind, const Direction& d) const;
  // Direction of the given kind closest to unit vector u.
  Direction FromUnit(DoaKind kind, const Eigen::Vector3d& u) const;
  // Relative delays tau_m(u) in seconds.
  Eigen::VectorXd Delays(const Eigen::Vector3d& u) const { return -(positions_m.transpose() * u) / speed_of_sound_mps; }
  // Uniform linear array: spacing, else 0.
  double UniformSpacing() const;
  // Throws std::invalid_argument when a microphone's device channel is not in audio blocks of
  // `block_channels` channels.
  void CheckChannels(int block_channels) const;
};

// Angle between two directions of a kind (on the sphere; 1-D: |difference|).
double AngularDistanceRad(const ArrayGeometry& geometry, DoaKind kind, const Direction& a,
                          const Direction& b);
using common::WrapAngle;  // to (-pi, pi]
double DegToRad(double d);
double RadToDeg(double r);

}  // namespace sound
}  // namespace sarmap
