#pragma once
// The online CI sound map behind `sarmap-sound-map` (no LCM): SLAM is the localisation map,
// this is the IDP EKF sound map (§4.3).
//   * POSE (current map_from_base + covariance + SLAM node id): the current pose of the sound
//     map follows it; between SLAM optimisations its covariance grows with the motion.
//   * DOA: associated to sources (track ids, chi-square gate, spectral signature); a new
//     source is anchored at the SLAM node of the latest POSE, and that node is requested
//     as an anchor (AnchorNodeIds()); a known one gets an EKF update.
//   * SLAM_ANCHORS: back-propagation (eqs. 4.20-4.25) of [current, anchors] into the sound
//     map; nothing flows back into SLAM.
//   * PEOPLE_AUDIO: a heard person's DOA track marks its source as a person.
// Inputs must arrive in time order (the node puts a TimeOrderedQueue in front).

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "common/options.h"
#include "sound_map/data_association.h"
#include "sound_map/idp_ekf.h"

namespace sarmap {
namespace sound_map {

struct OnlineSoundMapOptions {
  bool three_d = false;             // azimuth + elevation sources (3D arrays)
  double initial_range_m = 4.0;     // 1 / rho_0 at first observation
  double inverse_depth_sigma = 0.25;  // sigma_rho at first observation, 1/m
  double doa_sigma_floor_deg = 3.0;   // lower bound on the DOA std from the message
  double elevation_sigma_deg = 60.0;  // 3D map fed azimuth-only DOA: elevation prior
  double gate_chi2 = 9.0;             // association gate (unknown tracks)
  double update_gate_chi2 = 25.0;     // outlier gate on updates of an associated source (0: none)
  double max_signature_distance = 0.2;
  double motion_noise_m_per_m = 0.05;    // current-pose growth between SLAM updates
  double motion_noise_rad_per_m = 0.02;
  double motion_noise_rad_per_rad = 0.05;
  double converged_sigma_m = 0.5;   // converged when the largest position std is below
  double silent_after_s = 30.0;     // not heard for this long: STATE_SILENT
  // An unknown DOA track may join an existing source only if that source is converged and
  // has been quiet this long (else two nearby voices would merge).
  double reassociate_after_silence_s = 1.0;
  // Without a spectral signature a bearing alone rarely tells two sources apart: by default
  // only signatures (plus the bearing gate) re-associate, never the bearing alone.
  bool reassociate_without_signature = false;
  template <class V>
  void Visit(V& v) {
    v("three_d", three_d, "map sources in 3D (azimuth + elevation) instead of the plane");
    v("initial_range_m", initial_range_m, "range assumed at first observation (1/rho_0)");
    v("inverse_depth_sigma", inverse_depth_sigma, "std of the inverse depth at first observation, 1/m");
    v("doa_sigma_floor_deg", doa_sigma_floor_deg, "lower bound on the DOA std taken from DOA messages");
    v("elevation_sigma_deg", elevation_sigma_deg, "3D map, azimuth-only DOA: std of the 0-elevation prior");
    v("gate_chi2", gate_chi2, "chi-square gate for associating an unknown DOA track to a source");
    v("update_gate_chi2", update_gate_chi2, "chi-square outlier gate on source updates (0: none)");
    v("max_signature_distance", max_signature_distance, "spectral signature cosine distance gate");
    v("motion_noise_m_per_m", motion_noise_m_per_m, "current-pose position noise per metre between SLAM updates");
    v("motion_noise_rad_per_m", motion_noise_rad_per_m, "current-pose heading noise per metre");
    v("motion_noise_rad_per_rad", motion_noise_rad_per_rad, "current-pose heading noise per radian turned");
    v("converged_sigma_m", converged_sigma_m, "a source is converged when its largest position std is below this");
    v("silent_after_s", silent_after_s, "a source not heard for this long is reported silent");
    v("reassociate_after_silence_s", reassociate_after_silence_s,
      "an unknown DOA track may re-join a converged source quiet for this long");
    v("reassociate_without_signature", reassociate_without_signature,
      "allow re-association by the bearing gate alone when the DOA carries no spectral signature");
  }
  void Validate(common::Validator& check) const {
    check.Positive("initial_range_m", initial_range_m);
    check.Positive("inverse_depth_sigma", inverse_depth_sigma);
    check.Positive("doa_sigma_floor_deg", doa_sigma_floor_deg);
    check.Positive("elevation_sigma_deg", elevation_sigma_deg);
    check.Positive("gate_chi2", gate_chi2);
    check.NonNegative("update_gate_chi2", update_gate_chi2);
    check.InRange("max_signature_distance", max_signature_distance, 0, 2);
    check.NonNegative("motion_noise_m_per_m", motion_noise_m_per_m);
    check.NonNegative("motion_noise_rad_per_m", motion_noise_rad_per_m);
    check.NonNegative("motion_noise_rad_per_rad", motion_noise_rad_per_rad);
    check.Positive("converged_sigma_m", converged_sigma_m);
    check.Positive("silent_after_s", silent_after_s);
    check.NonNegative("reassociate_after_silence_s", reassociate_after_silence_s);
  }
};

class OnlineSoundMap {
 public:
  enum Kind { kAngle1d = 1, kAzimuth = 2, kAzimuthElevation = 3 };
  struct Doa {
    int64_t track_id = -1;
    int kind = kAzimuth;
    double azimuth_rad = 0, elevation_rad = 0;
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity() * 0.03;
    std::vector<double> signature;  // e.g. mean MFCCs; empty if none
  };
  struct Source {
    int64_t id;
    Eigen::Vector3d position_m;
    Eigen::Matrix3d covariance;
    enum State { kInitialising = 1, kConverged = 2, kSilent = 3 } state;
    int hypotheses_left = 1;
    bool is_person = false;
    int64_t first_heard_utime = 0, last_heard_utime = 0;
    int num_observations = 0;
  };
  struct Counters {
    int64_t doa_used = 0, doa_new_sources = 0, doa_reassociated = 0, doa_gated_out = 0;
    int64_t doa_unsupported_kind = 0, doa_before_pose = 0, back_propagations = 0, bad_anchors = 0;
    int64_t bad_poses = 0;
  };

  OnlineSoundMap(const OnlineSoundMapOptions& options, const ArrayMount& mount);

  void OnPose(int64_t utime, const Pose2& map_from_base, const Eigen::Matrix3d& covariance, int64_t node_id);
  // SLAM_ANCHORS: current pose, the kept anchors and the joint covariance (3(1+n) square).
  // Returns false (and counts) for an inconsistent message.
  bool OnSlamAnchors(int64_t utime, const Pose2& current, const std::vector<std::pair<int64_t, Pose2>>& anchors,
                     const Eigen::MatrixXd& covariance);
  void OnDoa(int64_t utime, const std::string& device, const std::vector<Doa>& doas);
  void OnHeardPerson(const std::string& device, int64_t track_id);

  // SLAM node ids this map needs kept (the anchors of its sources that came from SLAM).
  std::vector<int64_t> AnchorNodeIds() const;
  // True once since the anchor set last changed (time to send SLAM_ANCHOR_REQUEST).
  bool TakeAnchorsChanged();
  std::vector<Source> Sources(int64_t now_utime) const;
  // The source a DOA track was associated with, -1 if none.
  int64_t SourceOfTrack(const std::string& device, int64_t track_id) const {
    return associator_.SourceOfTrack(device, track_id);
  }
  const Counters& counters() const { return counters_; }
  const IdpEkf& ekf() const { return ekf_; }

 private:
  struct Meta {
    bool is_person = false;
    int64_t first = 0, last = 0;
    int n = 0;
  };
  OnlineSoundMapOptions options_;
  IdpEkf ekf_;
  SourceAssociator associator_;
  bool have_pose_ = false;
  Pose2 last_pose_;
  int64_t last_node_id_ = -1;
  int64_t next_local_anchor_ = -2;  // anchors without a SLAM node: negative ids
  int64_t next_source_id_ = 1;
  std::map<int64_t, Meta> meta_;
  bool Converged(int64_t id) const;
  bool anchors_changed_ = false;
  Counters counters_;
};

}  // namespace sound_map
}  // namespace sarmap
