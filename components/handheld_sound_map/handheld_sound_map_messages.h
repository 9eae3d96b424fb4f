#pragma once
// sarmap-handheld-sound-map's options and its LCM <-> core conversions (shared by the node and
// its tests): a hand-held RGB-D rig (RIG_POSE from sarmap-rgbd-odometry) with a linear array.

#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <vector>

#include "common/message_conversions.h"
#include "common/options.h"
#include "common/robot_config.h"
#include "common/stamp_gate.h"
#include "handheld_sound_map/linear_array_map.h"
#include "sarmap/doa_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/pose_t.hpp"
#include "sarmap/sound_map_t.hpp"

namespace sarmap {
namespace sound_map {

struct HandheldSoundMapOptions {
  std::string pose_channel = "RIG_POSE";  // sarmap-rgbd-odometry's odom_from_rig
  std::string doa_channel = "DOA_MAP";
  std::string people_audio_channel = "PEOPLE_AUDIO";
  std::string sound_map_channel = "SOUND_MAP";
  // The array in the rig frame (x forward, y left, z up). A Kinect held level: its bar (the
  // array's x axis, config/arrays/kinect.yaml) along the rig's y, 3 cm below the depth camera.
  common::ExtrinsicsOptions rig_from_mic_array{0.0, 0.0, -0.03, 0.0, 0.0, M_PI / 2};
  double reorder_delay_s = 0.5;   // inputs wait this long for older ones
  double publish_period_s = 1.0;  // SOUND_MAP period, message time
  common::StampGateOptions stamp_gate;  // each input stream on its own clock
  LinearArrayMapOptions map;
  template <class V>
  void Visit(V& v) {
    v("pose_channel", pose_channel, "the rig's 6-DoF pose in (pose_t, odom_from_rig)");
    v("doa_channel", doa_channel, "the linear array's DOAs in (doa_t, KIND_ANGLE_1D)");
    v("people_audio_channel", people_audio_channel, "heard people in (marks sources as persons)");
    v("sound_map_channel", sound_map_channel, "the sound map out");
    v("rig_from_mic_array", rig_from_mic_array,
      "the mic_array frame (its x axis along the linear array) in the rig frame; the default is "
      "a level Kinect's bar along the rig's y axis, 3 cm below the camera");
    v("reorder_delay_s", reorder_delay_s,
      "inputs are processed in time order once this much newer data arrived", NonNegative());
    v("publish_period_s", publish_period_s, "SOUND_MAP period, message time", Positive());
    v("stamp_gate", stamp_gate,
      "inputs stamped far from their stream's clock are dropped and counted, never adopted");
    v("map", map, "linear-array sound map (Su 2017 ch. 5)");
  }
};

// rig_from_sensor: the frame of LinearArraySoundMap, the array along +Y and x forward, from
// the mic_array frame whose x axis is the array: sensor y = mic x, sensor x = -mic y, i.e.
// mic_from_sensor = Rz(-90 deg).
inline Eigen::Isometry3d RigFromSensor(const common::ExtrinsicsOptions& rig_from_mic_array) {
  const common::Rigid3d r = rig_from_mic_array.ToRigid3d();
  Eigen::Isometry3d rig_from_mic = Eigen::Isometry3d::Identity();
  rig_from_mic.linear() = r.rotation().toRotationMatrix();
  rig_from_mic.translation() = r.translation();
  Eigen::Isometry3d mic_from_sensor = Eigen::Isometry3d::Identity();
  mic_from_sensor.linear() =
      Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return rig_from_mic * mic_from_sensor;
}

// pose_t (position, quaternion w x y z) as an isometry; false when not finite or not unit.
inline bool IsometryFromPose(const sarmap::pose_t& msg, Eigen::Isometry3d* out) {
  const Eigen::Quaterniond q(msg.orientation[0], msg.orientation[1], msg.orientation[2],
                             msg.orientation[3]);
  const Eigen::Vector3d t(msg.position_m[0], msg.position_m[1], msg.position_m[2]);
  if (!q.coeffs().allFinite() || !t.allFinite() || std::abs(q.norm() - 1.0) > 1e-3) return false;
  out->setIdentity();
  out->linear() = q.normalized().toRotationMatrix();
  out->translation() = t;
  return true;
}

// KIND_ANGLE_1D DOAs: the angle alpha to the array's axis (0..pi) is beta = pi/2 - alpha from
// broadside. Other kinds are counted in *skipped.
inline std::vector<LinearArraySoundMap::Doa> LinearDoasFromMessage(const sarmap::doa_t& msg,
                                                                   int64_t* skipped) {
  std::vector<LinearArraySoundMap::Doa> out;
  for (const auto& s : msg.sources) {
    if (s.kind != sarmap::doa_source_t::KIND_ANGLE_1D) {
      ++*skipped;
      continue;
    }
    LinearArraySoundMap::Doa d;
    d.track_id = s.track_id;
    d.beta_rad = M_PI / 2 - s.azimuth_rad;
    d.sigma_rad = std::sqrt(std::max(0.0, s.covariance[0]));
    out.push_back(d);  // non-finite values are counted by the map
  }
  return out;
}

// Heard people (CUE_HEARD) as beta directions of the same array.
inline std::vector<LinearArraySoundMap::Doa> HeardLinearDirections(
    const sarmap::people_detections_t& msg) {
  std::vector<LinearArraySoundMap::Doa> out;
  for (const auto& d : msg.detections) {
    if (d.cue != sarmap::person_detection_t::CUE_HEARD || !std::isfinite(d.azimuth_rad)) continue;
    LinearArraySoundMap::Doa doa;
    doa.beta_rad = M_PI / 2 - d.azimuth_rad;
    doa.sigma_rad = std::sqrt(std::max(0.0, static_cast<double>(d.direction_covariance[0])));
    out.push_back(doa);
  }
  return out;
}

inline sarmap::sound_map_t LinearSoundMapMessage(const LinearArraySoundMap& map, int64_t utime) {
  sarmap::sound_map_t msg{};  // value-initialised: every field the map does not set is 0
  msg.header.utime = utime;
  msg.header.frame = "map";
  for (const auto& s : map.sources()) {
    sarmap::sound_source_t out{};
    out.id = s.id;
    for (int i = 0; i < 3; ++i) out.position_m[i] = s.position_m[i];
    // A linear array hears a cone, not a bearing: a source is a position once its hypotheses
    // have converged; before, position_m is its best hypothesis and the bearing unknown.
    out.has_position = s.converged;
    for (int i = 0; i < 3; ++i) out.bearing_origin_m[i] = s.position_m[i];
    out.bearing_variance = M_PI * M_PI;
    common::FromCovariance3(s.covariance, out.covariance);
    // (unary + : the LCM constants are declared, not defined; no reference to them may be taken)
    out.state = s.converged ? +sarmap::sound_source_t::STATE_CONVERGED : +sarmap::sound_source_t::STATE_INITIALISING;
    out.hypotheses_left = s.hypotheses_left;
    out.is_person = s.is_person;
    out.first_heard_utime = s.first_heard;
    out.last_heard_utime = s.last_heard;
    out.num_observations = s.observations;
    msg.sources.push_back(out);
  }
  msg.num_sources = static_cast<int32_t>(msg.sources.size());
  return msg;
}

}  // namespace sound_map
}  // namespace sarmap
