#pragma once
// The people map (Sales 2014 §4.1.6, and beyond): people found by sight and by sound, in the
// map frame, merged, fused across cues, with a confidence that grows with evidence and decays
// without it. Free of LCM: the node feeds it detections already paired with the sensor pose
// at their capture time.
//
// Seen people: a 3D position in the camera frame with covariance, moved into the map with
//   p_map = R p_cam + t,   P_map = R P_cam R^T + J P_pose J^T
// where J = d p_map / d (x, y, yaw) of the robot pose (planar pose uncertainty).
// Detections within merge_radius_m (45 cm) of a person update it by information fusion
//   P = (P_old^-1 + P_z^-1)^-1,  x = P (P_old^-1 x_old + P_z^-1 z),
// with a floor on P because repeated detections share the pose error.
// Heard people: a direction only. A heard direction is associated with the SOUND_MAP source it
// points at (angle within a chi-square gate); a source so marked (or flagged is_person by the
// sound map) becomes a heard person at the source's position and covariance — the range comes
// from the robot's motion, not from an assumed 0.95 m. A heard person and a seen person whose
// positions agree (Mahalanobis gate in x, y) are one person with both cues.
// SLAM corrections: a seen person hangs from the SLAM graph node of the robot pose it was
// first seen from once reported (a candidate: its latest sighting), with that node's map pose
// then, T_old. When SLAM reports the node at T_new (its loop closures move old nodes), the
// person's seen estimate moves rigidly by T_new T_old^-1, as the map under it did; a heard
// estimate follows its sound source, which the sound map moves.
// Confidence: each detection of confidence c_d gives c <- 1 - (1 - c)(1 - gain c_d); without
// evidence it halves every confidence_half_life_s. A person is reported while c is at least
// min_report_confidence, and for good once c has reached keep_confidence: a victim found stays
// on the map however long the robot is elsewhere. A person only seen is reported only once
// detected in min_seen_detections frames, or again min_seen_span_s after the first detection:
// consecutive frames share their errors, so the confidence, which takes each detection as
// independent, is sure of a flicker too soon.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/options.h"
#include "common/time.h"
#include "common/transform.h"

namespace sarmap {
namespace people_map {

struct PeopleMapOptions {
  double merge_radius_m = 0.45;
  double fuse_gate_chi2 = 9.21;      // 99 % for 2 dof: heard and seen agree
  double fuse_max_distance_m = 1.5;  // and never further apart than this
  double heard_gate_chi2 = 6.63;     // 99 % for 1 dof: a heard direction points at a source
  double min_direction_sigma_rad = 0.05;
  double min_position_sigma_m = 0.05;  // floor of a seen person's position std
  double confidence_gain = 0.5;
  double confidence_half_life_s = 300.0;
  double min_report_confidence = 0.25;  // below this a person is kept but not reported
  double keep_confidence = 0.75;        // ... unless it once reached this
  int min_seen_detections = 1;  // a person only seen is reported after this many frames...
  double min_seen_span_s = 0;   // ... or when seen again this long after the first time
  double heard_person_window_s =
      30.0;  // a source counts as a person this long after a heard detection
  bool heard_needs_converged_source = true;  // an initialising source's position is still a guess
  // ... or one known to this largest planar std (m), converged or not (0: converged only).
  double heard_max_source_sigma_m = 0.0;
  int min_heard_calls =
      2;  // calls towards a source (within heard_person_window_s) to make it a person
  // One utterance often fires several keywords at once ("here", "help", "assist" within 0.3 s): the
  // hits towards one source closer than this to its previous call are that same call.
  double same_call_s = 2.0;
  // A track id of the detector seen again after longer than this is another track (the detector
  // restarted); its confirmation drops a track after n frames without a detection (0.33 s at
  // 15 Hz, 0.17 s at 30 Hz).
  double track_gap_s = 1.0;
  // Two sightings of one person at different times differ by the change of SLAM's pose error
  // between them, which SLAM's own covariance does not show: per axis, this std (0: none). A
  // detection that starts a sighting joins a seen person within sighting_gate_chi2 of it.
  double relative_pose_sigma_m = 0.27;
  double sighting_gate_chi2 = 9.21;  // 99 % for 2 dof
  template <class V>
  void Visit(V& v) {
    v("merge_radius_m", merge_radius_m, "detections this close (x, y) are the same place",
      Positive());
    v("fuse_gate_chi2", fuse_gate_chi2,
      "Mahalanobis gate (2 dof; 9.21 is 99 %) for a heard and a seen person to be one", Positive());
    v("fuse_max_distance_m", fuse_max_distance_m,
      "a heard and a seen person further apart are never fused", Positive());
    v("heard_gate_chi2", heard_gate_chi2,
      "gate (1 dof; 6.63 is 99 %) for a heard direction to point at a sound source", Positive());
    v("min_direction_sigma_rad", min_direction_sigma_rad, "floor of a heard direction's std",
      Positive());
    v("min_position_sigma_m", min_position_sigma_m, "floor of a seen person's position std",
      Positive());
    v("confidence_gain", confidence_gain, "how fast confidence grows with each detection (0..1)",
      InRange(0.0, 1.0));
    v("confidence_half_life_s", confidence_half_life_s,
      "confidence halves after this long without evidence", Positive());
    v("min_report_confidence", min_report_confidence,
      "people below this confidence are not reported, unless it once reached keep_confidence",
      InRange(0.0, 1.0));
    v("keep_confidence", keep_confidence,
      "a person whose confidence once reached this is reported for good, its confidence decaying "
      "(0.75: two full-confidence detections); above 1: never",
      Positive());
    v("min_seen_detections", min_seen_detections,
      "a person seen but not heard is reported only once detected in this many frames, or again "
      "min_seen_span_s after the first detection (the frames of one viewing are not independent "
      "evidence: furniture passing the detector's k-of-n for a moment is no person); 1: from the "
      "first detection",
      AtLeast(1));
    v("min_seen_span_s", min_seen_span_s,
      "... or once detected again this long after the first detection (a person seen in brief "
      "glimpses from different moments); 0: the frame count alone",
      NonNegative());
    v("heard_person_window_s", heard_person_window_s,
      "a sound source stays a person this long after being heard calling; min_heard_calls are "
      "counted within it, and a call towards a source that converges within it still places "
      "that caller",
      Positive());
    v("heard_needs_converged_source", heard_needs_converged_source,
      "a heard-only person is placed only at a converged sound source; a call towards an "
      "initialising "
      "source is remembered and places the person when the source converges");
    v("heard_max_source_sigma_m", heard_max_source_sigma_m,
      "with heard_needs_converged_source: a source whose largest planar position std is at most "
      "this is placed too, converged or not (0: converged sources only)",
      NonNegative());
    v("min_heard_calls", min_heard_calls,
      "a sound source becomes a heard person only after this many keyword calls towards it within "
      "heard_person_window_s: one keyword false alarm is not a person",
      AtLeast(1));
    v("same_call_s", same_call_s,
      "keyword hits towards a source within this long of its previous call are one call (one "
      "utterance "
      "often fires several keywords); 0: every hit is a call",
      NonNegative());
    v("track_gap_s", track_gap_s,
      "a detector track id seen again after longer than this is another track (one sighting "
      "ends)",
      Positive());
    v("relative_pose_sigma_m", relative_pose_sigma_m,
      "std per axis of the change of the robot pose error between two sightings of one person "
      "(SLAM drift that its covariance does not show); a new sighting joins a seen person it is "
      "within sighting_gate_chi2 of (0: only within merge_radius_m); a seen and a heard estimate "
      "are gated and fused with it too",
      NonNegative());
    v("sighting_gate_chi2", sighting_gate_chi2,
      "Mahalanobis gate (2 dof) for a new sighting to be a seen person", Positive());
  }
};

enum Cue : uint8_t { kSeenRgbd = 1, kSeenDepth = 2, kHeard = 4 };  // as mapped_person_t

struct SeenDetection {
  Eigen::Vector3d position_camera_m;
  Eigen::Matrix3d covariance_camera;
  double confidence = 1.0;
  Cue cue = kSeenRgbd;
  int64_t track_id = -1;  // the detector's track (one continuous viewing); -1: none
};

struct HeardDetection {
  double azimuth_rad = 0;  // in the mic_array frame
  double elevation_rad = 0;
  double azimuth_sigma_rad = 0.1;
  double confidence = 1.0;
  std::string keyword;
};

struct SoundSource {
  int64_t id = -1;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // map frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  bool is_person = false;
  bool converged = false;
};

struct Person {
  int64_t id = -1;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // fused estimate, map frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double confidence = 0;  // at last_detected_utime
  bool confirmed = false;  // confidence once reached keep_confidence: reported for good
  uint8_t cues = 0;
  int num_detections = 0;
  int people_count = 1;
  common::Utime first_detected_utime = 0;
  common::Utime last_detected_utime = 0;
  std::string keyword;
  int64_t sound_source_id = -1;
  // The SLAM node the seen estimate hangs from (-1: none, e.g. poses without a graph) and that
  // node's map pose when the estimate was last moved with it.
  int64_t anchor_node_id = -1;
  common::Rigid2d map_from_anchor_node;
  // The two estimates behind the fused one.
  bool has_seen = false;
  Eigen::Vector3d seen_position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d seen_covariance = Eigen::Matrix3d::Identity();
  bool has_heard = false;
  Eigen::Vector3d heard_position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d heard_covariance = Eigen::Matrix3d::Identity();
  // The seen estimate is the fusion of sightings. A sighting is one track of the detector (one
  // continuous viewing): its detections share one robot pose error, so their sensor noise
  // averages down but the pose error does not. The sightings before the current one, fused:
  bool has_settled = false;
  Eigen::Vector3d settled_position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d settled_covariance = Eigen::Matrix3d::Identity();
  // The current sighting: its track, the sum of its detections' sensor information (and of
  // information times position), and the pose part of its latest detection's covariance.
  int64_t sighting_track_id = -1;
  common::Utime sighting_last_utime = 0;
  int sighting_detections = 0;
  Eigen::Matrix3d sighting_information = Eigen::Matrix3d::Zero();
  Eigen::Vector3d sighting_information_position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sighting_pose_covariance = Eigen::Matrix3d::Zero();
};

// One seen detection as the map took it (for replay tools): where it landed in the map, with
// which covariance, and the person it updated or made.
struct SeenTrace {
  common::Utime utime = 0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position_camera_m = Eigen::Vector3d::Zero();
  int64_t person_id = -1;
  bool made_person = false;
};

// The SLAM graph node a robot pose hangs from (pose_t::node_id) and the node's map pose as known
// at that pose's time.
struct PoseNode {
  int64_t node_id = -1;  // -1: none
  common::Rigid2d map_from_node;
};

class PeopleMap {
 public:
  explicit PeopleMap(const PeopleMapOptions& options) : options_(options) {}
  // Called for every seen detection applied (replay tools; not saved).
  void set_seen_trace(std::function<void(const SeenTrace&)> trace) {
    seen_trace_ = std::move(trace);
  }

  // One frame of seen people. map_from_camera: camera pose at capture time;
  // pose_covariance: (x, y, yaw) covariance of the robot pose in the map.
  // node: the SLAM node of the robot pose (a new seen person is anchored to it).
  void AddSeen(common::Utime utime, const std::vector<SeenDetection>& detections,
               const common::Rigid3d& map_from_camera, const Eigen::Matrix3d& pose_covariance,
               const Eigen::Vector2d& robot_xy, const PoseNode& node = {});
  // SLAM's latest map poses of graph nodes: every seen person anchored at one of them moves by
  // its node's correction. Returns how many people moved.
  int MoveWithNodes(const std::map<int64_t, common::Rigid2d>& map_from_node);
  // The SLAM nodes the seen people hang from, sorted (what to ask SLAM to keep and report): at
  // most max_nodes (0: all), those of confirmed people first, then of the people seen last.
  // With now >= 0 only the people reported at `now`: a candidate that is never reported keeps
  // no SLAM submap alive over a long mission.
  std::vector<int64_t> AnchorNodeIds(size_t max_nodes = 0, common::Utime now = -1) const;
  // SLAM started a new graph (its node ids began again): the people stay where they are and
  // hang from no node until seen again.
  void ForgetAnchors();
  // Heard people from one analysis block; map_from_mic: array pose at capture time.
  // Returns how many were associated with a sound source.
  int AddHeard(common::Utime utime, const std::vector<HeardDetection>& detections,
               const common::Rigid3d& map_from_mic);
  // The latest sound-source map.
  void UpdateSoundSources(common::Utime utime, const std::vector<SoundSource>& sources);

  // People to report at `utime` (confidence decayed to that time), sorted by id.
  std::vector<Person> Report(common::Utime utime) const;
  const std::map<int64_t, Person>& people() const { return people_; }
  double DecayedConfidence(const Person& p, common::Utime utime) const;
  // On the map at `utime`: confirmed, or confidence at least min_report_confidence.
  bool Reported(const Person& p, common::Utime utime) const;

  // Crash-safe state: a sealed YAML file (common/state_file.h: kind "people-map", version and
  // CRC-32), written to a temporary file, then renamed over `path`.
  void Save(const std::string& path) const;
  // Returns false (state unchanged) when the file does not exist; throws (state unchanged) on a
  // file of another kind or version, a checksum mismatch, unparsable YAML or a non-finite value.
  // An unsealed version-1 file (written before sealing) is read as it is.
  bool Load(const std::string& path);
  static constexpr const char* kStateKind = "people-map";
  static constexpr int kStateVersion = 2;

 private:
  void AddEvidence(Person* p, common::Utime utime, double detection_confidence) const;
  void Refuse(Person* p) const;  // recompute the fused estimate from seen and heard
  void MergeCloseSeenPeople();
  // What the person's settled sightings and the current one say together; false when the
  // current one is degenerate.
  bool SettledWithSighting(const Person& p, Eigen::Vector3d* x, Eigen::Matrix3d* P) const;
  // The current sighting is fused into the settled estimate and closed.
  void CloseSighting(Person* p) const;
  // seen_position_m / seen_covariance from the settled estimate and the current sighting.
  void UpdateSeen(Person* p) const;
  Person* NearestSeen(const Eigen::Vector3d& position_m, double radius_m);

  PeopleMapOptions options_;
  std::function<void(const SeenTrace&)> seen_trace_;
  std::map<int64_t, Person> people_;
  std::map<int64_t, SoundSource> sources_;
  std::map<int64_t, common::Utime> source_heard_utime_;  // source -> last heard calling
  std::map<int64_t, std::string> source_keyword_;
  // source -> its recent calls (saved)
  std::map<int64_t, std::vector<common::Utime>> source_call_utimes_;
  // A second sound source of one caller (the sound map split one voice in two): source -> the
  // person it was merged into (not saved: a restart merges again).
  std::map<int64_t, int64_t> source_alias_;
  int RecentCalls(int64_t source_id, common::Utime utime) const;
  // Planar Mahalanobis distance^2 of a seen and a heard estimate, with the change of the pose
  // error between sighting and hearing (relative_pose_sigma_m) in the covariance.
  double HeardSeenMahalanobis2(const Eigen::Vector3d& seen_m,
                               const Eigen::Matrix3d& seen_covariance,
                               const Eigen::Vector3d& heard_m,
                               const Eigen::Matrix3d& heard_covariance) const;
  // The fusion gate: a seen and a heard estimate within fuse_max_distance_m and, by
  // HeardSeenMahalanobis2, within fuse_gate_chi2 are one person.
  bool HeardAgreesWithSeen(const Eigen::Vector3d& seen_m, const Eigen::Matrix3d& seen_covariance,
                           const Eigen::Vector3d& heard_m,
                           const Eigen::Matrix3d& heard_covariance) const;
  // A new person with the next id, first and last detected at `utime`.
  Person* NewPerson(common::Utime utime);
  // relative_pose_sigma_m^2 on x and y.
  Eigen::Matrix3d RelativePoseCovariance() const;
  // The source's position is settled enough to place a heard-only person there.
  bool Placed(const SoundSource& s) const;
  int64_t next_id_ = 1;
};

}  // namespace people_map
}  // namespace sarmap
