#pragma once
// An EKF over a planar robot pose, kept anchor poses, range-bearing landmarks and sound
// sources in inverse-depth parametrisation (IDP) anchored at kept poses (Su 2017 §4.3).
//
// State x = [current (x y yaw) | blocks in insertion order], each block one of
//   anchor    (x y yaw)          a past robot pose from which sources were first heard
//   landmark  (x y)              seen by a range-bearing sensor
//   source    (theta [phi] rho)  IDP ray from its anchor's array origin (eq. 4.3 / 4.4)
//
// One class serves the three filters of §4.4.1:
//   * the CI sound map: current + anchors + sources; it is not predicted by odometry but fed
//     after every localisation-map update by BackPropagate() (eqs. 4.20-4.25), so nothing
//     flows back into the localisation map;
//   * the localisation map of the simulations (odometry + landmarks + anchors);
//   * the "full SLAM" EKF (odometry + landmarks + sources in one state) for comparison.
// Updates are the standard EKF (eqs. 4.8-4.10); only the columns an observation touches are
// used to build the gain, so an update costs O(n^2) for n states.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <vector>

#include "common/binary_io.h"
#include "sound_map/sound_geometry.h"

namespace sarmap {
namespace sound_map {

class IdpEkf {
 public:
  struct Options {
    bool three_d = false;  // sources (theta, phi, rho) observed by azimuth + elevation
    ArrayMount mount;      // mic_array in base
    double initial_inverse_depth = 0.25;  // rho_0 at first observation, 1/m
    double inverse_depth_sigma = 0.25;    // sigma_rho at first observation, 1/m
    double initial_elevation_sigma_rad = 0;  // extra elevation variance at init (3D), rad
    // false: DOA updates only correct the sources (Schmidt-Kalman: the current pose and the
    // anchors are "consider" states whose mean and covariance stay what the localisation map
    // said). The CI sound map fed by SLAM wants this: its poses are copies of SLAM's, which
    // the next POSE and SLAM_ANCHORS overwrite, so a DOA that nudged them would leave the
    // sources offset against the anchors they hang from.
    bool source_updates_move_poses = true;
    // BackPropagate: true, eq. 4.25 also moves the sources by their regression on the anchors'
    // correction (x_S += K12 dx); false, the sources move rigidly with their anchors (the ray's
    // origin is the anchor's array position; its azimuth turns by the anchor's heading change).
    // The regression is exact for a joint Gaussian; with a weakly observed inverse depth and
    // anchors that DOAs nudged, K12 can turn a 0.1 m / 1.4 deg anchor correction into a 2 m move
    // of the source.
    bool back_propagate_sources = true;
  };

  explicit IdpEkf(const Options& options);

  void Reset(const Pose2& current, const Eigen::Matrix3d& covariance);

  // Odometry prediction x <- x ∘ u with u ~ N(odometry, q) in the robot frame.
  void Predict(const Pose2& odometry, const Eigen::Matrix3d& q);
  // Replaces the current pose's mean (the localisation map's latest estimate), keeping the
  // covariance.
  void SetCurrentMean(const Pose2& current) { x_.head<3>() = current.vec(); }

  // Keeps a copy of the current pose (fully correlated with it) as anchor `id`.
  void AddAnchor(int64_t id);
  bool HasAnchor(int64_t id) const { return anchors_.count(id) > 0; }

  // Range-bearing landmarks: z = (range_m, bearing_rad), r its covariance.
  void AddLandmark(int64_t id, const Eigen::Vector2d& z, const Eigen::Matrix2d& r);
  bool HasLandmark(int64_t id) const { return landmarks_.count(id) > 0; }
  // Returns the innovation's chi-square; no update when it exceeds `gate` (<= 0: no gate).
  double UpdateLandmark(int64_t id, const Eigen::Vector2d& z, const Eigen::Matrix2d& r,
                        double gate = 0);

  // Sound sources: z = azimuth (2D) or (azimuth, elevation) (3D) in the array frame, r its
  // covariance. The source is anchored at anchor `anchor_id` (added from the current pose
  // when missing), its ray direction taken from z and its inverse depth from the options.
  void AddSource(int64_t id, int64_t anchor_id, const Eigen::VectorXd& z, const Eigen::MatrixXd& r);
  bool HasSource(int64_t id) const { return sources_.count(id) > 0; }
  // Chi-square of z against the source's predicted bearing (for gating / association).
  double SourceChi2(int64_t id, const Eigen::VectorXd& z, const Eigen::MatrixXd& r) const;
  double UpdateSource(int64_t id, const Eigen::VectorXd& z, const Eigen::MatrixXd& r,
                      double gate = 0);
  void RemoveSource(int64_t id);
  // Drops an anchor no source uses any more (no-op if a source still uses it).
  void RemoveAnchor(int64_t id);

  // Back-propagation from the localisation map (eqs. 4.20-4.25). The shared part x_C is the
  // current pose and the listed anchors (those this map holds); `covariance` is the joint
  // covariance of [current, anchors...] in the order given (3 per pose). Everything else
  // (IDP rays, inverse depths, anchors not listed) is x_S and moves by K12 = P_SC P_C^-1.
  // keep_covariance: only the means move (x_C = SLAM's, x_S += K12 dx with this map's own
  // K12); P stays this map's (for a localisation map whose covariance is not trusted).
  void BackPropagate(const Pose2& current, const std::vector<std::pair<int64_t, Pose2>>& anchors,
                     const Eigen::MatrixXd& covariance, bool keep_covariance = false);

  // Mean and joint covariance of [current, anchors in `ids` order] (what a localisation
  // map hands the sound map; slam_anchors_t carries the same).
  void SharedState(const std::vector<int64_t>& ids, Pose2* current,
                   std::vector<std::pair<int64_t, Pose2>>* anchors, Eigen::MatrixXd* covariance) const;

  Pose2 current() const { return Pose2::FromVec(x_.head<3>()); }
  Eigen::Matrix3d current_covariance() const { return p_.topLeftCorner<3, 3>(); }
  Pose2 anchor(int64_t id) const;
  // Covariance of an anchor's (x, y, yaw).
  Eigen::Matrix3d anchor_covariance(int64_t id) const {
    const int a = anchors_.at(id);
    return p_.block<3, 3>(a, a);
  }
  Eigen::Vector2d landmark(int64_t id) const;
  Eigen::Matrix2d landmark_covariance(int64_t id) const;
  // Map-frame point of a source (z includes the array height) and its covariance. Sources
  // whose inverse depth is not positive are reported at 1/1e-3 m along the ray.
  void SourcePoint(int64_t id, Eigen::Vector3d* point, Eigen::Matrix3d* covariance) const;
  int64_t source_anchor(int64_t id) const { return sources_.at(id).anchor; }
  // Inverse depth rho of a source (1/m) and its variance.
  void SourceInverseDepth(int64_t id, double* rho, double* variance) const {
    const int i = sources_.at(id).index + source_dim() - 1;
    *rho = x_[i];
    *variance = p_(i, i);
  }
  // Map-frame azimuth theta of a source's ray and its variance.
  void SourceBearing(int64_t id, double* theta, double* variance) const {
    const int i = sources_.at(id).index;
    *theta = x_[i];
    *variance = p_(i, i);
  }
  std::vector<int64_t> source_ids() const;
  std::vector<int64_t> anchor_ids() const;
  int dim() const { return static_cast<int>(x_.size()); }
  // The filter's state (not its options), for a restart from a state file.
  void Save(common::BinaryWriter* w) const;
  void Load(common::BinaryReader* r);
  const Eigen::VectorXd& mean() const { return x_; }
  const Eigen::MatrixXd& covariance() const { return p_; }
  const Options& options() const { return options_; }

 private:
  struct Source {
    int index;
    int64_t anchor;
  };
  int source_dim() const { return options_.three_d ? 3 : 2; }
  int obs_dim() const { return options_.three_d ? 2 : 1; }
  int Append(int n, bool angle_first);
  // Generic EKF correction with the observation Jacobian over the columns `cols`.
  double Correct(const std::vector<int>& cols, const Eigen::MatrixXd& h, const Eigen::VectorXd& nu,
                 const Eigen::MatrixXd& r, double gate, bool fix_poses = false);
  // The innovation z - h(x) of source `id` (bearing wrapped), its Jacobian `h` and the state
  // columns `cols` it is non-zero on.
  Eigen::VectorXd SourceInnovation(int64_t id, const Eigen::VectorXd& z, Eigen::MatrixXd* h,
                                   std::vector<int>* cols) const;
  void WrapAngles();
  void RemoveBlock(int i, int n);

  Options options_;
  Eigen::VectorXd x_;
  Eigen::MatrixXd p_;
  std::vector<char> is_angle_;
  std::map<int64_t, int> anchors_;
  std::map<int64_t, int> landmarks_;
  std::map<int64_t, Source> sources_;
};

}  // namespace sound_map
}  // namespace sarmap
