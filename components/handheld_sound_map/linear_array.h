#pragma once
// Sound-source mapping with a linear microphone array (Su 2017 ch. 5).
//
// A linear array along its sensor's +Y axis hears one angle per source,
//   beta = atan2(p_y, sqrt(p_x^2 + p_z^2))                                  (5.2)
// so a source lies on a cone. A new source gets N_h hypotheses s = (beta, gamma, rho)
// (axis angle, circumferential angle, inverse depth; 5.8-5.11), anchored on the array
// axis at the first observation, x_axis = (x, y, z, theta, phi) (5.9), each an EKF
// (5.13-5.18) with covariance diag(P_beta, (pi/N_h)^2, sigma_rho^2) (5.12). A hypothesis
// whose mean chi-square (5.21-5.22) exceeds a threshold is pruned; it has converged when
// its linearity index (5.23-5.27) is small. Once all survivors have converged their mean
// Euclidean point joins the joint optimisation (5.28-5.32) of 6-DoF keyframe poses,
// RGB-D landmarks and sources: over the last keyframes online, over everything at a loop
// closure.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "handheld_sound_map/doa_sensor_model.h"

namespace sarmap {
namespace sound_map {

// The anchor frame of the hypotheses (5.9): origin and the azimuth/elevation of the
// array's +Y axis at the first observation. Its rotation is f_eul_mat(theta - pi/2, 0, phi):
// yaw theta - pi/2 then roll phi, which carries +Y onto the axis.
struct ArrayAxis {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double theta = 0, phi = 0;
  static ArrayAxis FromPose(const Eigen::Isometry3d& world_from_sensor);
  Eigen::Matrix3d rotation() const;
};

// Euclidean point of s = (beta, gamma, rho) on `axis` (5.19).
Eigen::Vector3d HypothesisPoint(const ArrayAxis& axis, const Eigen::Vector3d& s);
// Predicted beta of point p from sensor pose (5.1-5.2, 5.20).
double LinearArrayBeta(const Eigen::Isometry3d& world_from_sensor, const Eigen::Vector3d& p);

struct MultiHypothesisOptions {
  int num_hypotheses = 10;           // N_h (Table 5.1)
  double min_distance_m = 0.4;       // d_min: rho_0 = 1 / (3 d_min), sigma_rho = rho_0
  double prune_mean_chi2 = 4.0;      // prune when the mean chi-square exceeds this
  // ... or exceeds the quantile of chi2(n)/n at this many standard scores (3.09: 99.9 %;
  // 0: off), which tightens the bound as a hypothesis collects observations.
  double prune_z = 3.09;
  int prune_min_observations = 3;
  double linearity_threshold = 0.3;  // converged when L_d < this (Civera: 0.1)
  // (5.23): h from the anchor (the thesis; then L_d = 4 sigma_rho / rho) or, false, from the
  // current sensor position (Civera et al.'s original linearity index).
  bool linearity_from_anchor = false;
  // (5.21): S = H P H' as printed in the thesis, or, true, H P H' + Q (the innovation covariance).
  bool chi2_with_noise = true;
  int min_observations = 8;          // and at least this many updates
  // Survivors that have converged to different places (a mirror image of the cone) are not
  // averaged: all must lie within this radius of their mean, else the ones whose mean
  // chi-square is clearly worse than the best one's are pruned (our addition).
  double cluster_radius_m = 0.5;
  // A level array moved only in its own plane hears a source and its reflection through that
  // plane at the same angles: survivors in two mirror-image clusters never agree. With this,
  // such a source converges to their mean, on the plane (its height unknown; our addition
  // for a robot-borne or level-carried array).
  bool converge_mirror_pairs = false;
  // Likelihood-ratio pruning against the best hypothesis (our addition; 0: off).
  double relative_prune_chi2 = 12.0;
  int relative_prune_min_observations = 10;
  double relative_prune = 1.5;
};

class MultiHypothesisSource {
 public:
  struct Hypothesis {
    Eigen::Vector3d s;  // beta, gamma, rho
    Eigen::Matrix3d p;
    double chi2_sum = 0;
    int updates = 0;
    bool alive = true;
    double linearity = 1e9;
  };
  MultiHypothesisSource(const MultiHypothesisOptions& options, const Eigen::Isometry3d& pose, double beta,
                        double beta_variance);
  // One observation (GP-corrected beta, variance) from `pose` (5.13-5.18, 5.21-5.27).
  void Update(const Eigen::Isometry3d& pose, double beta, double beta_variance);
  // Survivors all converged: the mean of their points (the joint optimisation's guess).
  bool converged() const;
  Eigen::Vector3d MeanPoint() const;
  int alive() const;
  double chi2(const Eigen::Isometry3d& pose, double beta, double beta_variance) const;  // best hypothesis
  const std::vector<Hypothesis>& hypotheses() const { return hypotheses_; }
  bool AllLinear() const;   // every survivor's linearity index is below the threshold
  bool Clustered() const;   // survivors agree on one place
  // ... once each is reflected to the upper side of the anchor's horizontal plane.
  bool ClusteredUpToMirror() const;
  // Every survivor fails the chi-square test (5.22) that pruned the others: the cone was
  // seeded from a bad first DOA, or the pruning removed the right part of it on an outlier.
  // Such a source must be started again, not converged.
  bool Failed() const;
  const ArrayAxis& axis() const { return axis_; }

 private:
  MultiHypothesisOptions options_;
  ArrayAxis axis_;
  std::vector<Hypothesis> hypotheses_;
};

// ---- simulation of §5.5.1 (Table 5.1) ----
struct LinearSimConfig {
  int trajectory = 1;             // 1: sources in front (Fig. 5.6); 2: sources at the side (Fig. 5.7)
  double step_m = 0.2;            // Table 5.1
  double odo_sigma_m = 0.01;      // per step and axis (our choice: the thesis tracks with ORB-SLAM)
  double odo_sigma_rad = 0.5 * M_PI / 180;
  // Landmarks per m^2 of floor (heights +-1.5 m): 15 gives ~195 seen per keyframe, the map points
  // an ORB-SLAM2 RGB-D tracker keeps of the 1000 ORB features per image that the thesis' own
  // settings extract (SSM_LinearArray kinect_settings.yaml: ORBextractor.nFeatures 1000).
  // 2 gives ~25 per keyframe (the unit tests' density); 0.6 leaves the poses 1.2-1.6 deg off.
  double landmark_density_per_m2 = 15.0;
  double landmark_range_m = 4.0;
  double landmark_fov_rad = 60 * M_PI / 180;  // half angle
  double landmark_sigma_m = 0.01;             // Table 5.1
  double landmark_sigma_rad = 1.0 * M_PI / 180;
  double sound_range_m = 3.0;                 // Table 5.1
  // Height of the "up and down" moves (the thesis does not give it; our choice).
  double updown_m = 0.6;
  double heard_probability = 1.0;
  // Trajectory 1: on the arcs round a source the sensor faces the source turned by this
  // much; NaN (default): it faces along the path like a walking operator. (0 would put
  // both sources of a pair at beta = 0 whatever their height, leaving it unobservable.)
  double arc_face_offset_rad = NAN;
  // Trajectory 1: keep facing along the side (+x on the first) through the arcs instead.
  bool fixed_heading = false;
  double doa_noise_scale = 1.0;   // multiplies SimulatedDoaSigma (1: Table 5.1's 10-20 deg)
  // The DOA method's raw angle given the true one (§5.5.1: the error of a real array's DOA
  // method, measured every 5 deg, modelled by a GP over the true angle and added to the
  // truth): raw = mean + sqrt(var) n of doa_generator->Predict(true beta). Null: Gaussian
  // noise of SimulatedDoaSigma, unbiased (the 10-20 deg of Table 5.1 read as pure noise).
  std::shared_ptr<const DoaSensorModel> doa_generator;
  double doa_quantum_rad = 0;     // raw angles rounded to this grid (the SRP-PHAT grid: 5 deg); 0: off
  uint64_t seed = 1;
};

// The real calibration pairs (raw DOA estimate, true angle), radians, from a CSV with columns
// raw_deg,true_deg (shared/data/audio/ssm/gp_doa_calibration.csv: the thesis' PS3-Eye/Kinect
// array, 37 angles x 10 trials). Throws std::invalid_argument when unreadable.
void LoadDoaCalibrationCsv(const std::string& path, std::vector<double>* raw_rad, std::vector<double>* true_rad);
// The sensor models of §5.5.1 from calibration pairs. `generator` is the forward model: the
// raw estimate's mean g(b) and variance given the true angle b (a GP over the true angle;
// the simulated sensor, and what LinearMapperOptions::forward_model wants). `sensor_model`
// maps a raw estimate back to the true angle by inverting the generator with Bayes' rule
// (BayesInvertedDoaModel; raw angles on a grid of step quantum_rad). `thesis_model` is the
// thesis' own map back, a GP of the truth over the raw angle (5.5-5.6), kept for comparison:
// fitted on noisy inputs it flattens the correction.
struct CalibratedDoa {
  std::shared_ptr<const DoaSensorModel> generator;
  std::shared_ptr<const DoaSensorModel> sensor_model;
  std::shared_ptr<const DoaSensorModel> thesis_model;
};
CalibratedDoa FitCalibratedDoa(const std::vector<double>& raw_rad,
                               const std::vector<double>& true_rad, double quantum_rad = 0);
// DOA noise of the simulated array: 10 deg broadside growing to 20 deg at endfire
// (Table 5.1: "10-20 deg").
double SimulatedDoaSigma(double true_beta_rad);

struct LinearSimData {
  LinearSimConfig config;
  std::vector<Eigen::Isometry3d> truth;     // world_from_sensor (x fwd, y = array axis, z up)
  std::vector<Eigen::Isometry3d> odometry;  // odometry[k]: pose k-1 -> k
  struct Landmark {
    int64_t id;
    Eigen::Vector3d z;  // range, azimuth, elevation in the sensor frame
  };
  struct Sound {
    int64_t source;
    double raw_beta;    // the DOA method's angle (noisy, clipped to +-90 deg)
  };
  std::vector<std::vector<Landmark>> landmark_obs;
  std::vector<std::vector<Sound>> sound_obs;
  std::vector<Eigen::Vector3d> sources;
  std::vector<Eigen::Vector3d> landmarks;
};
LinearSimData SimulateLinear(const LinearSimConfig& config);
// The calibration set of the simulated array: 37 true angles (-90..90, 5 deg) x 10 trials.
void SimulatedCalibration(uint64_t seed, std::vector<double>* raw, std::vector<double>* truth);

// ---- the mapper ----
struct LinearMapperOptions {
  MultiHypothesisOptions hypotheses;
  int num_hypotheses = 10;    // copied into hypotheses.num_hypotheses
  int window_keyframes = 5;   // online joint optimisation over the last keyframes (§5.5.1)
  // A source the joint optimisation carries farther than this from every pose that heard it
  // has run off along an asymptote of its cone (far away its angles barely change); it keeps
  // its place from before that solve (our addition; Table 5.1's array hears to 3 m).
  double max_source_range_m = 15.0;
  int loop_gap_keyframes = 60;  // a landmark re-seen after this many keyframes: loop closure
  std::shared_ptr<const DoaSensorModel> sensor_model;  // default: GP fitted on SimulatedCalibration
  // The DOA method's forward model (true -> raw mean and variance). When set, the joint
  // optimisation compares the raw angle with g(beta) of the estimate instead of the
  // corrected angle with beta (see RawBetaCost); `sensor_model` still seeds the hypotheses.
  std::shared_ptr<const DoaSensorModel> forward_model;
  double doa_quantum_rad = 0;  // the raw angles' grid step (its q^2/12 joins the raw variance)
  // On convergence and after the final optimisation, keep a source or its mirror image
  // through the horizontal plane of the poses that heard it, whichever explains its DOAs
  // better (a level array cannot tell them apart from one height).
  bool mirror_check = true;
  double converged_error_m = 1.0;  // for the score only
  // Diagnostic: every source is known at its true position from its first observation
  // (skips the multi-hypothesis initialisation; shows the accuracy floor of the data).
  bool oracle_init = false;
  // Diagnostic: the keyframe poses are the true ones and held fixed.
  bool oracle_poses = false;
};

struct LinearRunResult {
  double rms_m = 0;               // over sources that converged: sqrt(mean |p - p_true|^2)
  double axis_rms_m = 0;          // same errors per axis: sqrt(mean over sources and x,y,z)
  // Accuracy floor: per source, least squares of its DOAs from the TRUE poses, started at
  // the truth; RMS over all heard sources.
  double floor_rms_m = 0;
  double pose_rms_m = 0, pose_rms_rad = 0;  // final keyframe poses against the truth
  std::vector<double> errors_m;   // per source (NaN: not converged)
  double convergence_rate = 0;    // converged (linearity index) / number of sources
  double correct_convergence_rate = 0;  // converged and within converged_error_m of the truth
  int converged = 0;
  int full_optimisations = 0;
  int restarted_sources = 0;  // initialisations started again (MultiHypothesisSource::Failed)
  std::vector<Eigen::Vector3d> estimates;
  std::vector<bool> source_converged;
  double seconds = 0;
};
LinearRunResult RunLinearArrayMapping(const LinearSimData& data, const LinearMapperOptions& options);

}  // namespace sound_map
}  // namespace sarmap
