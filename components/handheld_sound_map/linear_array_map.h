#pragma once
// The online linear-array sound map of Su 2017 ch. 5, for a 6-DoF pose source such as a
// hand-held RGB-D rig (sarmap-rgbd-odometry) carrying a linear microphone array (a Kinect).
//
// Inputs: the rig's poses from its odometry (odom_from_sensor, the sensor frame having the
// array along +Y, x forward) and the array's DOAs as beta, the angle from broadside towards +Y
// (5.1-5.2). Per source: N_h (beta, gamma, rho) hypotheses anchored on the array axis at the
// first DOA (5.8-5.20), chi-square pruning (5.21-5.22), convergence by linearity index
// (5.23-5.27); a converged source joins the joint optimisation of the last
// `window_keyframes` keyframe poses and the sources they heard (5.28-5.32), with the
// odometry's relative motion between keyframes as residuals. `Finish()` (and every
// `full_optimisation_keyframes`) optimises everything. Without landmarks or loop closures
// from the pose source, the sources' DOAs are what corrects the odometry here.
//
// Data association: a DOA whose track id is bound to a source goes to it (a converged source:
// only within `update_gate_chi2`, or of its mirror image, which flips it; a track that misses
// `track_release_misses` times in a row is released). A new track's first
// `confirm_observations` DOAs decide: the converged source whose gate (`gate_chi2`) every one
// of them passes (a source heard again under a new track id), else a new source; a track that
// fits a known source waits until its DOAs come from places far enough apart to have told that
// source from another emitter on its cone (parallax of sqrt(gate_chi2) DOA sigmas). Untracked
// DOAs go to the best source under the gate, else start one. Converged duplicates (one
// emitter initialised under two track ids) merge. One DOA per source per block. A source that never
// converged and was not heard for `prune_after_s` with fewer than `prune_min_observations` DOAs is
// removed.
//
// No LCM here: sarmap-handheld-sound-map is the node, and the simulation tests drive this
// class directly.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <vector>

#include "common/options.h"
#include "common/time.h"
#include "handheld_sound_map/linear_array.h"

namespace sarmap {
namespace sound_map {

struct LinearArrayMapOptions {
  MultiHypothesisOptions hypotheses;  // N_h (num_hypotheses) and the pruning / convergence tests
  double keyframe_distance_m = 0.2;   // Table 5.1's odometry step
  double keyframe_angle_deg = 10.0;
  int window_keyframes = 5;  // §5.5.1: the last 5 poses
  int full_optimisation_keyframes =
      50;  // also optimise everything every this many keyframes (0: only at Finish)
  // Relative-pose noise of the pose source between keyframes: sigma = floor + per_m * distance.
  double odometry_sigma_m_per_m = 0.02;
  double odometry_sigma_floor_m = 0.005;
  double odometry_sigma_deg_per_m = 1.0;
  double odometry_sigma_floor_deg = 0.2;
  double doa_sigma_floor_deg = 3.0;  // the DOA's reported sigma is floored at this
  double gate_chi2 = 9.0;            // association of a DOA to any source (1 dof)
  double update_gate_chi2 = 25.0;    // a DOA of a source's own track
  int confirm_observations =
      3;  // a new track's DOAs that decide: a known source heard again, or a new one
  int track_release_misses =
      5;  // a track whose DOAs miss its source this many times in a row is released
  int associate_min_observations = 10;  // an initialising source gates others' DOAs after this many
  double max_pose_gap_s = 0.5;          // a DOA needs a pose within this (no extrapolation)
  double prune_after_s = 20.0;
  int prune_min_observations = 15;
  bool mirror_check = true;  // keep a source or its mirror through the poses' plane, the better
  // Heard only from poses within this height of each other, a source's height is one of two
  // (it and its mirror image through their plane fit alike): its z variance grows to say so.
  double level_height_spread_m = 0.1;
  // Converged duplicates (one source, several track ids) merge when this close.
  double merge_radius_m = 0.5;
  // A solve that carries a source farther than this from every pose that heard it is undone
  // for that source (it ran off along an asymptote of its cone, where its angles barely change).
  double max_source_range_m = 15.0;
  template <class V>
  void Visit(V& v) {
    v("num_hypotheses", hypotheses.num_hypotheses,
      "N_h: initial hypotheses on a new source's cone (5.10; Table 5.1: 10)");
    v("min_distance_m", hypotheses.min_distance_m,
      "d_min: rho_0 = 1/(3 d_min), sigma_rho = rho_0 (5.12)");
    v("prune_mean_chi2", hypotheses.prune_mean_chi2,
      "prune a hypothesis whose mean chi-square exceeds this (5.22)");
    v("prune_z", hypotheses.prune_z, "... or the chi2(n)/n quantile at this z (0: off)");
    v("linearity_threshold", hypotheses.linearity_threshold,
      "converged when every survivor's linearity index is below this (5.27)");
    v("min_observations", hypotheses.min_observations, "updates before a hypothesis may converge");
    v("cluster_radius_m", hypotheses.cluster_radius_m,
      "survivors must agree within this radius to converge");
    v("keyframe_distance_m", keyframe_distance_m, "a new keyframe after this much motion",
      Positive());
    v("keyframe_angle_deg", keyframe_angle_deg, "... or this much rotation", Positive());
    v("window_keyframes", window_keyframes,
      "online joint optimisation over the last keyframes (5.28-5.32)", AtLeast(1));
    v("full_optimisation_keyframes", full_optimisation_keyframes,
      "optimise every keyframe and source every this many keyframes (0: only at the end)",
      AtLeast(0));
    v("odometry_sigma_m_per_m", odometry_sigma_m_per_m,
      "pose source's translation noise per metre travelled", NonNegative());
    v("odometry_sigma_floor_m", odometry_sigma_floor_m, "... plus this per keyframe step",
      Positive());
    v("odometry_sigma_deg_per_m", odometry_sigma_deg_per_m,
      "pose source's rotation noise per metre travelled", NonNegative());
    v("odometry_sigma_floor_deg", odometry_sigma_floor_deg, "... plus this per keyframe step",
      Positive());
    v("doa_sigma_floor_deg", doa_sigma_floor_deg, "lower bound of a DOA's standard deviation",
      Positive());
    v("gate_chi2", gate_chi2, "association gate of a DOA to a source (chi-square, 1 dof)",
      Positive());
    v("update_gate_chi2", update_gate_chi2, "gate of a DOA whose track belongs to the source",
      Positive());
    v("confirm_observations", confirm_observations,
      "a new DOA track joins a converged source only when this many of its DOAs all pass that "
      "source's gate",
      AtLeast(1));
    v("track_release_misses", track_release_misses,
      "a DOA track missing its source this many times in a row is released (the tracker's id "
      "moved)",
      AtLeast(1));
    v("associate_min_observations", associate_min_observations,
      "an initialising source takes other tracks' DOAs after this many");
    v("max_pose_gap_s", max_pose_gap_s, "a DOA without a pose within this is dropped", Positive());
    v("prune_after_s", prune_after_s,
      "remove a source not converged and not heard for this long ...", Positive());
    v("prune_min_observations", prune_min_observations, "... with fewer DOAs than this");
    v("max_source_range_m", max_source_range_m,
      "a source the optimisation carries farther than this from every pose that heard it keeps its "
      "place from before",
      Positive());
    v("merge_radius_m", merge_radius_m,
      "two converged sources this close are one (heard under two track ids)", NonNegative());
    v("level_height_spread_m", level_height_spread_m,
      "a source heard only from poses within this height of each other has two possible heights "
      "(its z variance says so)",
      NonNegative());
    v("mirror_check", mirror_check,
      "keep a source or its reflection through the mean height of the poses that heard it, the "
      "better");
  }
  void Validate(common::Validator& c) const {
    c.That(hypotheses.num_hypotheses >= 1, "num_hypotheses", "must be >= 1");
    c.Positive("min_distance_m", hypotheses.min_distance_m);
    c.Positive("prune_mean_chi2", hypotheses.prune_mean_chi2);
    c.Positive("linearity_threshold", hypotheses.linearity_threshold);
    c.That(hypotheses.min_observations >= 1, "min_observations", "must be >= 1");
    c.Positive("cluster_radius_m", hypotheses.cluster_radius_m);
  }
};

class LinearArraySoundMap {
 public:
  // One DOA of the linear array: beta from broadside towards the sensor's +Y (the array axis),
  // in [-pi/2, pi/2], with its standard deviation.
  struct Doa {
    int64_t track_id = -1;
    double beta_rad = 0;
    double sigma_rad = 0;
  };
  struct Source {
    int64_t id = 0;
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // map frame
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
    bool converged = false;
    int hypotheses_left = 0;
    int observations = 0;
    bool is_person = false;
    common::Utime first_heard = 0, last_heard = 0;
    std::vector<int64_t> track_ids;  // DOA track ids bound to it now
  };
  struct Counters {
    int64_t poses = 0, doas = 0, doas_used = 0;
    int64_t doas_without_pose = 0, doas_invalid = 0, doas_duplicate = 0, doas_gated_out = 0;
    int64_t sources_born = 0, sources_restarted = 0, sources_converged = 0, sources_pruned = 0,
            sources_merged = 0;
    int64_t mirrors_flipped = 0, keyframes = 0, window_optimisations = 0, full_optimisations = 0;
    int64_t runaway_solves = 0;  // a source carried beyond max_source_range_m, put back
  };

  explicit LinearArraySoundMap(const LinearArrayMapOptions& options);
  ~LinearArraySoundMap();
  LinearArraySoundMap(const LinearArraySoundMap&) = delete;
  LinearArraySoundMap& operator=(const LinearArraySoundMap&) = delete;

  // The pose source's odom_from_sensor at `utime` (non-finite poses are ignored).
  void OnPose(common::Utime utime, const Eigen::Isometry3d& odom_from_sensor);
  // One analysis block's DOAs (times must not go back: the node orders its inputs).
  void OnDoa(common::Utime utime, const std::vector<Doa>& doas);
  // A heard person's direction (PEOPLE_AUDIO): the source it gates to is a person.
  // Returns false when it gates to none.
  bool OnHeardDirection(common::Utime utime, const Doa& doa);
  // Optimise every keyframe and converged source (the end of a run).
  void Finish();

  std::vector<Source> sources() const;
  // The current sensor pose in the map frame (the odometry corrected by the optimisation);
  // false before the first keyframe.
  bool CurrentPose(Eigen::Isometry3d* map_from_sensor) const;
  // map_from_odom: where the corrections moved the odometry frame, at the newest keyframe.
  Eigen::Isometry3d MapFromOdom() const;
  const Counters& counters() const { return counters_; }
  size_t num_keyframes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Counters counters_;
};

}  // namespace sound_map
}  // namespace sarmap
