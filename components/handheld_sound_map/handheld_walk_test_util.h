#pragma once
// A hand-held rig's walk for the hand-held sound map's tests (not part of a library): the rig
// walks 3 m along x and 2 m along y, raised and lowered by 0.3 m as a hand does, past a source
// at (2, 2.5, 1.3). The Kinect's bar (the array's x axis) lies along the rig's y, 3 cm below the
// camera (config/handheld_sound_map.yaml). Step k is at 1 s + k x 0.1 s.

#include <Eigen/Geometry>
#include <cmath>

#include "sarmap/doa_t.hpp"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace sound_map {
namespace testing_util {

constexpr int kWalkSteps = 125;
inline Eigen::Vector3d WalkSource() { return Eigen::Vector3d(2.0, 2.5, 1.3); }

// RIG_POSE of step k.
inline pose_t WalkPose(int k) {
  const double s = 0.04 * k;  // path length
  Eigen::Isometry3d odom_from_rig = Eigen::Isometry3d::Identity();
  const double yaw = s < 3.0 ? 0.0 : M_PI / 2;
  odom_from_rig.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  odom_from_rig.translation() =
      s < 3.0 ? Eigen::Vector3d(s, 0, 0) : Eigen::Vector3d(3.0, s - 3.0, 0);
  odom_from_rig.translation().z() = 1.2 + 0.3 * std::sin(2 * M_PI * s / 1.5);
  pose_t pose{};
  pose.header.utime = 1000000 + k * 100000;
  pose.header.frame = "odom";
  pose.child_frame = "rig";
  const Eigen::Quaterniond q(odom_from_rig.linear());
  pose.orientation[0] = q.w();
  pose.orientation[1] = q.x();
  pose.orientation[2] = q.y();
  pose.orientation[3] = q.z();
  for (int i = 0; i < 3; ++i) pose.position_m[i] = odom_from_rig.translation()[i];
  pose.node_id = -1;
  return pose;
}

// DOA_MAP of step k, 1 us after its pose: the source's cone angle (+-1.5 deg of noise) as
// KIND_ANGLE_1D, and the same angle as another kind (which the map ignores and counts).
inline doa_t WalkDoa(int k) {
  const pose_t pose = WalkPose(k);
  Eigen::Isometry3d odom_from_rig = Eigen::Isometry3d::Identity();
  odom_from_rig.linear() = Eigen::Quaterniond(pose.orientation[0], pose.orientation[1],
                                              pose.orientation[2], pose.orientation[3])
                               .toRotationMatrix();
  odom_from_rig.translation() =
      Eigen::Vector3d(pose.position_m[0], pose.position_m[1], pose.position_m[2]);
  Eigen::Isometry3d rig_from_mic = Eigen::Isometry3d::Identity();
  rig_from_mic.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  rig_from_mic.translation() = Eigen::Vector3d(0, 0, -0.03);
  const Eigen::Vector3d p_mic = (odom_from_rig * rig_from_mic).inverse() * WalkSource();
  doa_t doa{};
  doa.header.utime = pose.header.utime + 1;
  doa.header.frame = "mic_array";
  doa.device_id = "kinect";
  doa_source_t d{};
  d.track_id = 3;
  d.kind = doa_source_t::KIND_ANGLE_1D;
  d.method = doa_source_t::METHOD_SRP_PHAT;
  d.confidence = 1;
  d.azimuth_rad = std::acos(p_mic.x() / p_mic.norm()) + 1.5 * M_PI / 180 * std::sin(7.3 * k);
  d.covariance[0] = std::pow(3 * M_PI / 180, 2);
  d.covariance[3] = 1;
  doa.sources.push_back(d);
  doa_source_t azimuth = d;
  azimuth.kind = doa_source_t::KIND_AZIMUTH;
  azimuth.track_id = 4;
  doa.sources.push_back(azimuth);
  doa.num_sources = 2;
  return doa;
}

}  // namespace testing_util
}  // namespace sound_map
}  // namespace sarmap
