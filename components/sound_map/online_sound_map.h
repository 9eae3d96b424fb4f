#pragma once
// The online CI sound map behind `sarmap-sound-map` (no LCM): SLAM is the localisation map,
// this is the IDP EKF sound map (§4.3).
//   * POSE (current map_from_base + covariance + SLAM node id): the current pose of the sound
//     map follows it; between SLAM optimisations its covariance grows with the motion.
//   * DOA: associated to a source by the chi-square gate on its predicted bearing (and the
//     spectral signature when both carry one); the DOA track id is only a hint (localiser
//     tracks churn). A DOA no source explains feeds a tentative map-frame bearing track; after
//     a few consistent DOAs it becomes a source anchored at the SLAM node of the latest POSE,
//     and that node is requested as an anchor (AnchorNodeIds()). Sources that never get
//     support are pruned. KIND_ANGLE_1D (linear arrays) gives two mirror sources (+/- the cone
//     angle); the one the DOAs stop explaining is removed.
//   * SLAM_ANCHORS: back-propagation (eqs. 4.20-4.25) of [current, anchors] into the sound
//     map; nothing flows back into SLAM.
//   * PEOPLE_AUDIO: a heard person's DOA track marks its source as heard (calling, when a
//     keyword came with it).
//   * Classes: each DOA's sound class (voice, alarm, machinery, music) is a vote for its
//     source; the source's class is the class with most votes once it has min_class_votes.
//   * Published (Sources): a source's range is observable when its inverse depth rho exceeds
//     observable_sigmas times its standard deviation (the 3-sigma range interval is bounded)
//     and its largest planar position std is below max_position_sigma_m. Until then it is a
//     bearing from its anchor (has_position false), never a position; so is a source placed
//     beyond site_margin_m of the mapped site. A source is a person
//     only when it was heard (PEOPLE_AUDIO), its class is voice, its position is observable
//     and it lies within site_margin_m of the mapped site (SetSite; no site known: anywhere).
// Inputs must arrive in time order (the node puts a TimeOrderedQueue in front).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/options.h"
#include "sound_map/bearing_evidence.h"
#include "sound_map/data_association.h"
#include "sound_map/idp_ekf.h"

namespace sarmap {
namespace sound_map {

struct OnlineSoundMapOptions {
  bool three_d = false;               // azimuth + elevation sources (3D arrays)
  double initial_range_m = 4.0;       // 1 / rho_0 at first observation
  double inverse_depth_sigma = 0.25;  // sigma_rho at first observation, 1/m
  double doa_sigma_floor_deg = 3.0;   // lower bound on the DOA std from the message
  double elevation_sigma_deg = 60.0;  // 3D map fed azimuth-only DOA: elevation prior
  double gate_chi2 = 9.0;             // association gate (unknown tracks)
  double update_gate_chi2 = 25.0;     // outlier gate on updates of an associated source (0: none)
  double max_signature_distance = 0.2;
  double motion_noise_m_per_m = 0.05;  // current-pose growth between SLAM updates
  double motion_noise_rad_per_m = 0.02;
  double motion_noise_rad_per_rad = 0.05;
  double converged_sigma_m = 0.5;  // converged when the largest position std is below
  // Range observability (published position vs bearing only).
  double observable_sigmas = 3.0;
  double max_position_sigma_m = 2.0;
  double site_margin_m = 1.0;  // a person, and a placed source, lie this close to the mapped site
  int min_class_votes = 3;     // DOAs with a class needed before a source has one
  // A person's source is a voice by a clear majority: a source's DOAs are classed one by one,
  // and a machine or an alarm heard together with voices gets many DOAs classed voice.
  double person_min_voice_share = 0.8;
  double silent_after_s = 30.0;  // not heard for this long: STATE_SILENT
  // Births: a DOA that fits no source starts a tentative track in the map frame; it becomes a
  // source after birth_min_observations DOAs whose map-frame bearings agree (chi-square
  // birth_gate_chi2 with a drift allowance) within birth_window_s. Single spurious DOAs
  // (reflections, noise bursts, localiser track churn) never enter the EKF.
  int birth_min_observations = 3;
  double birth_window_s = 2.0;
  double birth_gate_chi2 = 9.0;
  double birth_drift_deg_per_s = 6.0;  // the bearing of a static source turns as the robot moves
  // Pruning: a source that is not converged, has fewer than prune_min_observations and was
  // not heard for prune_after_s is removed (it never got support).
  double prune_after_s = 10.0;
  int prune_min_observations = 10;
  // A source whose inverse depth is negative by more than this many standard deviations lies
  // behind its anchor: its bearings do not meet at one point (a mixture of a source and its
  // reflection, or a moving source). It is removed (0: never).
  double prune_behind_sigmas = 3.0;
  // Linear arrays (KIND_ANGLE_1D, angle to the array axis = mic_array x): the planar bearing
  // is +angle or -angle. Both mirror sources are born; a mirror that misses this many
  // consecutive DOAs its twin explains is removed.
  int mirror_prune_misses = 3;
  // DOAs come from analysis windows of a few hundred ms, smoothed by the localiser's tracker:
  // while the robot turns fast they lag its heading by tens of degrees. They are dropped when
  // the heading changed faster than this between the last two poses (0: keep all).
  double max_turn_rate_deg_per_s = 10.0;
  // Azimuth + elevation DOAs steeper than this above or below the array plane are dropped
  // (0: keep all). A planar array cannot tell up from down, and a direction that steep is the
  // robot's own motors under the array (simulated robot: 77 deg) or a source within a few
  // decimetres of it; as a bearing on the map it is a source that follows the robot, and it
  // converged on the robot's own path as a ghost (corridor: a "person" on the path).
  double max_abs_elevation_deg = 60.0;
  // A converged source whose planar position lies within this distance of where the robot's
  // base has been is removed (0: never): a sound source cannot stand where the robot drove.
  // Such sources are ghosts: the robot's own noise, or a far talker's slightly biased bearings
  // seen straight ahead with no parallax (corridor: triangulated onto the path).
  double path_clearance_m = 0.25;
  // DOA updates also correct the current pose and anchors (plain EKF) instead of only the
  // sources (Schmidt-Kalman, the poses being SLAM's).
  bool doa_moves_poses = true;
  // SLAM's joint covariance comes from the pose graph's weights and is far tighter than its
  // real error (simulated lab: ~0.2 mm / 0.005 deg reported, 0.07 m / 1 deg RMS measured).
  // Taken as is, the sound map trusts every pose exactly and the DOAs' disagreement caused by
  // the pose errors drives the inverse depths astray. Each pose of SLAM_ANCHORS gets at least
  // this much independent uncertainty (added to its diagonal block; 0: SLAM's as is).
  double anchor_sigma_floor_m = 0.0;
  double anchor_sigma_floor_deg = 0.0;
  // false: SLAM_ANCHORS moves the current pose and the anchors (and, by K12, the sources) to
  // SLAM's means but keeps this map's own covariance of them (grown by the motion noise since
  // each anchor was made) instead of SLAM's. SLAM's relative node covariance is orders of
  // magnitude below its real error (see above), and every SLAM_ANCHORS (after each
  // optimisation, seconds apart) would reset the current-to-anchor uncertainty to it.
  bool use_slam_covariance = true;
  // true: SLAM_ANCHORS is applied only when its optimisation found new loop closures (and the
  // first one); false: after every optimisation, as the thesis does.
  bool anchors_after_loop_closure_only = false;
  // SLAM_ANCHORS also moves the sources by eq. 4.25's regression on the anchors' correction
  // (true), or only rigidly with their anchors, keeping their anchor-relative IDP parameters
  // (false). See IdpEkf::Options::back_propagate_sources.
  bool back_propagate_sources = true;
  // Sources where the bearings cross (bearing_evidence.h): every DOA, also those heard while
  // turning, solved as a batch; a source there that no EKF source explains is published too.
  BearingEvidenceOptions evidence;
  template <class V>
  void Visit(V& v) {
    v("three_d", three_d, "map sources in 3D (azimuth + elevation) instead of the plane");
    v("initial_range_m", initial_range_m, "range assumed at first observation (1/rho_0)",
      Positive());
    v("inverse_depth_sigma", inverse_depth_sigma,
      "std of the inverse depth at first observation, 1/m", Positive());
    v("doa_sigma_floor_deg", doa_sigma_floor_deg,
      "lower bound on the DOA std taken from DOA messages", Positive());
    v("elevation_sigma_deg", elevation_sigma_deg,
      "3D map, azimuth-only DOA: std of the 0-elevation prior", Positive());
    v("gate_chi2", gate_chi2, "chi-square gate for associating an unknown DOA track to a source",
      Positive());
    v("update_gate_chi2", update_gate_chi2, "chi-square outlier gate on source updates (0: none)",
      NonNegative());
    v("max_signature_distance", max_signature_distance, "spectral signature cosine distance gate",
      InRange(0, 2));
    v("motion_noise_m_per_m", motion_noise_m_per_m,
      "current-pose position noise per metre between SLAM updates", NonNegative());
    v("motion_noise_rad_per_m", motion_noise_rad_per_m, "current-pose heading noise per metre",
      NonNegative());
    v("motion_noise_rad_per_rad", motion_noise_rad_per_rad,
      "current-pose heading noise per radian turned", NonNegative());
    v("converged_sigma_m", converged_sigma_m,
      "a source is converged when its largest position std is below this", Positive());
    v("silent_after_s", silent_after_s, "a source not heard for this long is reported silent",
      Positive());
    v("observable_sigmas", observable_sigmas,
      "a source has a position once its inverse depth exceeds this many of its standard "
      "deviations",
      Positive());
    v("max_position_sigma_m", max_position_sigma_m,
      "... and its largest planar position std is below this", Positive());
    v("site_margin_m", site_margin_m,
      "a person must lie within this distance of the mapped site's known cells' box; a source "
      "placed beyond it is published as a bearing",
      NonNegative());
    v("min_class_votes", min_class_votes,
      "classified DOAs a source needs before it has a class (unknown until then)", AtLeast(1));
    v("person_min_voice_share", person_min_voice_share,
      "a source is a person only when at least this share of its classified DOAs are voice",
      InRange(0, 1));
    v("birth_min_observations", birth_min_observations,
      "consistent DOAs needed before a new source is born", AtLeast(1));
    v("birth_window_s", birth_window_s, "a tentative source must gather its DOAs within this time",
      Positive());
    v("birth_gate_chi2", birth_gate_chi2,
      "chi-square gate between map-frame bearings of a tentative source", Positive());
    v("birth_drift_deg_per_s", birth_drift_deg_per_s,
      "bearing drift allowed between DOAs of a tentative source", NonNegative());
    v("prune_after_s", prune_after_s,
      "an unconverged source with little support is removed after this silence", Positive());
    v("prune_min_observations", prune_min_observations,
      "sources with at least this many DOAs are never pruned", NonNegative());
    v("prune_behind_sigmas", prune_behind_sigmas,
      "remove a source whose inverse depth is below zero by this many standard deviations (0: "
      "never)",
      NonNegative());
    v("max_turn_rate_deg_per_s", max_turn_rate_deg_per_s,
      "DOAs heard while the robot turns faster than this are dropped (0: keep all)", NonNegative());
    v("max_abs_elevation_deg", max_abs_elevation_deg,
      "DOAs steeper than this above or below the array plane are dropped (robot's own motors; 0: "
      "keep all)",
      InRange(0, 90));
    v("path_clearance_m", path_clearance_m,
      "a converged source within this distance of where the robot drove is removed as a ghost (0: "
      "never)",
      NonNegative());
    v("doa_moves_poses", doa_moves_poses,
      "DOA updates also correct the current pose and anchors (false: only the sources; the poses "
      "are SLAM's)");
    v("anchor_sigma_floor_m", anchor_sigma_floor_m,
      "position std added to every pose of SLAM_ANCHORS (SLAM's covariance is overconfident; 0: as "
      "is)",
      NonNegative());
    v("anchor_sigma_floor_deg", anchor_sigma_floor_deg,
      "heading std added to every pose of SLAM_ANCHORS (0: as is)", NonNegative());
    v("use_slam_covariance", use_slam_covariance,
      "take SLAM_ANCHORS' joint covariance (true) or only its means, keeping this map's pose "
      "covariance (false)");
    v("anchors_after_loop_closure_only", anchors_after_loop_closure_only,
      "apply SLAM_ANCHORS only when SLAM found new loop closures (false: after every optimisation, "
      "as the thesis)");
    v("back_propagate_sources", back_propagate_sources,
      "SLAM_ANCHORS also regresses the sources on the anchors' correction (eq. 4.25; false: "
      "sources move rigidly with their anchors)");
    v("mirror_prune_misses", mirror_prune_misses,
      "linear arrays: a mirror source is removed after this many DOAs only its twin explains",
      AtLeast(1));
    v("evidence", evidence, "sources where the bearings cross (every DOA, a batch solve)");
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
    int sound_class = 0;            // kClass*; 0 unknown
    bool called = false;            // heard directions (PEOPLE_AUDIO): a keyword came with it
  };
  enum SoundClass {
    kClassUnknown = 0,
    kClassVoice = 1,
    kClassAlarm = 2,
    kClassMachinery = 3,
    kClassMusic = 4
  };
  enum Priority { kPriorityNone = 0, kPriorityVoice = 1, kPriorityCall = 2 };
  struct Source {
    int64_t id;
    Eigen::Vector3d position_m;
    Eigen::Matrix3d covariance;
    enum State { kInitialising = 1, kConverged = 2, kSilent = 3 } state;
    int hypotheses_left = 1;
    bool is_person = false;
    int64_t first_heard_utime = 0, last_heard_utime = 0;
    int num_observations = 0;
    // Range observable: position_m is the source. Otherwise it is a bearing: position_m and
    // covariance are the bearing origin's (the array at its anchor).
    bool has_position = false;
    Eigen::Vector3d bearing_origin_m = Eigen::Vector3d::Zero();
    double bearing_rad = 0, bearing_variance = 0;  // map frame
    int sound_class = kClassUnknown;
    double class_confidence = 0;  // vote share of that class
    int priority = kPriorityNone;
    bool inside_site = true;
  };
  struct Counters {
    int64_t doa_used = 0, doa_new_sources = 0, doa_reassociated = 0, doa_gated_out = 0;
    int64_t doa_unsupported_kind = 0, doa_before_pose = 0, back_propagations = 0, bad_anchors = 0;
    int64_t bad_poses = 0, anchors_skipped = 0;
    int64_t doa_tentative = 0, tentatives_expired = 0, sources_pruned = 0, mirrors_pruned = 0;
    int64_t doa_angle_1d = 0, doa_while_turning = 0, sources_behind = 0, doa_too_steep = 0;
    int64_t sources_on_path = 0;
    int64_t evidence_solves = 0;
  };

  OnlineSoundMap(const OnlineSoundMapOptions& options, const ArrayMount& mount);

  void OnPose(int64_t utime, const common::Rigid2d& map_from_base,
              const Eigen::Matrix3d& covariance, int64_t node_id);
  // SLAM_ANCHORS: current pose, the kept anchors and the joint covariance (3(1+n) square).
  // Returns false (and counts) for an inconsistent message.
  // loop_closed: the optimisation found new loop closures (slam_anchors_t::loop_closed); with
  // anchors_after_loop_closure_only a message without is skipped (counted, returns true).
  bool OnSlamAnchors(int64_t utime, const common::Rigid2d& current,
                     const std::vector<std::pair<int64_t, common::Rigid2d>>& anchors,
                     const Eigen::MatrixXd& covariance, bool loop_closed = true);
  void OnDoa(int64_t utime, const std::string& device, const std::vector<Doa>& doas);
  void OnHeardPerson(const std::string& device, int64_t track_id, bool called = false);
  // The mapped site: the box of the known cells of the localisation map (map frame).
  void SetSite(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m);
  // PEOPLE_AUDIO by direction (array frame, at the current pose): the source whose predicted
  // bearing gates it best (chi-square gate_chi2) is a person. For when the heard person's track
  // ids come from another DOA stream than the map's (sarmap-speech beams at DOA, the map reads
  // DOA_MAP). Returns the source marked, -1 if none.
  int64_t OnHeardDirection(const Doa& doa);

  // SLAM node ids this map needs kept (the anchors of its sources that came from SLAM).
  std::vector<int64_t> AnchorNodeIds() const;
  // True once since the anchor set last changed (time to send SLAM_ANCHOR_REQUEST).
  bool TakeAnchorsChanged();
  std::vector<Source> Sources(int64_t now_utime) const;
  // The source a DOA track was associated with, -1 if none.
  int64_t SourceOfTrack(const std::string& device, int64_t track_id) const {
    return associator_.SourceOfTrack(device, track_id);
  }
  // The SLAM node an EKF anchor (ekf().source_anchor()) hangs from, -1 for a local anchor.
  int64_t AnchorNode(int64_t ekf_anchor) const {
    auto it = anchor_links_.find(ekf_anchor);
    return it == anchor_links_.end() ? -1 : it->second.node;
  }
  const Counters& counters() const { return counters_; }
  const IdpEkf& ekf() const { return ekf_; }
  // The sources where the bearings cross, as of the latest solve (all of them, also those an
  // EKF source explains), and the number of rays kept.
  const std::vector<BearingEvidence::Source>& evidence_sources() const { return evidence_sources_; }
  size_t evidence_rays() const { return evidence_.size(); }

  // The whole state (not the options), crash-safe (written beside and renamed over path) and
  // sealed with a checksum (common/state_file.h), so a restarted node continues where it was.
  // Load returns false when there is no file and throws for one that is truncated, bit-flipped,
  // corrupt or from a map of the other dimension (three_d), leaving the map as it was.
  void Save(const std::string& path) const;
  bool Load(const std::string& path);

 private:
  struct Meta {
    bool is_person = false;  // heard (PEOPLE_AUDIO); a person when Sources() says so
    bool called = false;
    std::array<double, 5> class_votes{};
    int64_t first = 0, last = 0;
    int n = 0;
    int64_t twin = -1;  // linear arrays: the mirror source born with this one
    int mirror_misses = 0;
  };
  // A bearing-only track in the map frame waiting for enough support to become a source.
  struct Tentative {
    int64_t first = 0, last = 0;
    double bearing_map_rad = 0;  // latest map-frame bearing
    double variance = 0;         // its variance, rad^2
    int n = 0;
    int64_t track_id = -1;
    std::string device;
    int64_t twin = -1;  // index key of the mirror tentative (linear arrays)
  };
  // Observation of one DOA in the form the EKF takes, with its mirror for linear arrays.
  struct Obs {
    Eigen::VectorXd z;
    Eigen::MatrixXd r;
    bool mirrored = false;  // z[0] may also be -z[0]
  };
  bool MakeObs(const Doa& doa, Obs* obs) const;
  // Chi-square of obs against a source, choosing the mirror sign; *z_used the observation to apply.
  double Chi2(int64_t source, const Obs& obs, Eigen::VectorXd* z_used) const;
  void Tentate(int64_t utime, const std::string& device, const Doa& doa, const Obs& obs);
  void Birth(int64_t utime, int64_t key, const Obs& obs, double azimuth_rad);
  void Prune(int64_t utime);
  void Remove(int64_t source);
  std::map<int64_t, Tentative> tentatives_;
  int64_t next_tentative_ = 1;
  OnlineSoundMapOptions options_;
  IdpEkf ekf_;
  SourceAssociator associator_;
  bool have_pose_ = false;
  Pose2 last_pose_;
  int64_t last_pose_utime_ = 0;
  double yaw_rate_rad_per_s_ = 0;  // between the last two poses (signed, left positive)
  int64_t last_node_id_ = -1;
  int64_t next_local_anchor_ = -2;  // anchors without a SLAM node: negative ids
  int64_t next_source_id_ = 1;
  std::map<int64_t, Meta> meta_;
  bool Converged(int64_t id) const;
  bool have_site_ = false;
  Eigen::Vector2d site_min_ = Eigen::Vector2d::Zero(), site_max_ = Eigen::Vector2d::Zero();
  bool anchors_changed_ = false;
  Counters counters_;
  // A source's anchor is the pose it was first heard from, which is the SLAM node named by
  // the POSE of that moment composed with an offset (POSE is the latest scan's pose; nodes
  // are only made every node_max_distance/angle/time). The EKF's anchors therefore have their
  // own ids; each remembers its node and node_from_anchor, and SLAM_ANCHORS' node poses are
  // carried to the anchors through that offset before the back-propagation.
  struct AnchorLink {
    int64_t node = -1;
    Pose2 node_from_anchor;
  };
  std::map<int64_t, AnchorLink> anchor_links_;  // EKF anchor id -> node (+ offset)
  std::map<int64_t, Pose2> node_poses_;         // latest estimate of each SLAM node seen
  // Where the base has been (map frame, POSE as received, a point every trail_step_m_),
  // hashed in square cells of path_clearance_m so a lookup reads the 3x3 cells around it.
  std::unordered_map<int64_t, std::vector<Eigen::Vector2d>> trail_cells_;
  Eigen::Vector2d last_trail_point_{NAN, NAN};
  static constexpr double trail_step_m_ = 0.1;
  int64_t TrailCell(int64_t ix, int64_t iy) const { return (ix << 32) ^ (iy & 0xffffffff); }
  void AddToTrail(const Eigen::Vector2d& p);
  bool OnTrail(const Eigen::Vector2d& p) const;
  int64_t next_anchor_id_ = 0;
  int64_t AnchorForBirth();
  // Where the bearings cross: the rays, the latest solve and its sources' ids (kept across
  // solves for a source within twice peak_radius_m of where it was).
  BearingEvidence evidence_;
  std::vector<BearingEvidence::Source> evidence_sources_;
  std::vector<int64_t> evidence_ids_;
  int64_t next_evidence_id_ = kFirstEvidenceId;
  int64_t last_solve_utime_ = 0;
  static constexpr int64_t kFirstEvidenceId = 1000000000;
  void AddRay(int64_t utime, const Doa& doa, bool heard);
  // A source's class from its class votes, its priority, whether it lies inside the site and
  // whether it is a person (needs position_m and has_position set).
  void Classify(const std::array<double, 5>& class_votes, bool heard, bool called, Source* s) const;
  void SolveEvidence(int64_t utime);
};

}  // namespace sound_map
}  // namespace sarmap
