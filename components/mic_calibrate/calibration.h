#pragma once
// Microphone-array calibration by graph least squares (Su 2017, ch. 3).
//
// Unknowns: every microphone's position m_n, start offset tau_n and clock drift delta_n
// (relative to microphone 1, the reference), and the sound-source position s_k at each
// emission k = 1..K. Measurements: the TDOA of every microphone against the reference,
//
//   z_n(k) = (|m_n - s_k| - |s_k|) / c + tau_n + t_k * delta_n          (thesis eq. 3.18/3.30)
//
// (microphone 1 sits at the origin, so |m_1 - s_k| = |s_k|; t_k = k * dt in the thesis),
// with noise sigma_tdoa, and a random-walk prior between consecutive source positions,
//
//   s_k - s_{k-1} ~ N(0, sigma_rw^2 I)                                  (eq. 3.5/3.6)
//
// The maximum-likelihood estimate minimises the sum of squared whitened residuals, solved by
// Ceres (Levenberg-Marquardt, SPARSE_NORMAL_CHOLESKY with SuiteSparse) from several random
// initialisations; the best final cost wins.
//
// Gauge (what the TDOAs cannot see: a rigid motion and a mirror of everything):
//   mic `ref` at the origin with tau = delta = 0; mic `x_axis` on +x (y = z = 0);
//   2D: mic `plane` has y > 0; 3D: mic `plane` has z = 0 and y > 0, mic `z_axis` has z > 0.
// The signs are fixed after the solve by mirroring the whole solution (a mirror leaves every
// distance, hence the cost, unchanged).
//
// Variants: planar (2D), 3d, linear (known spacing along x, far-field source angle beta_k,
// z_n(k) = -x_n cos(beta_k) / c + tau_n + t_k delta_n, eq. 3.49; offsets and drift only),
// and synchronous arrays (tau = delta = 0, positions only). `estimate_drift = false` is the
// "ignore the clock difference" ablation of the thesis (Fig. 3.13).

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/options.h"

namespace sarmap {
namespace mic_calibrate {

struct SolverOptions {
  std::string geometry = "planar";  // planar | 3d | linear
  bool synchronous = false;         // true: tau = delta = 0, positions only
  bool estimate_drift = true;       // false: delta held at 0 (thesis Fig. 3.13 ablation)
  // Positions known (e.g. a Kinect-like array of separate sound cards whose geometry is the
  // datasheet's): held at the guess' positions (mic 1 moved to the origin); only start
  // offsets, drifts and the source positions are estimated. Any geometry, collinear included.
  bool known_positions = false;
  // 3d: known microphone heights (z in the gauge frame, one per mic, e.g. measured with a
  // tape when the gauge mics span the horizontal plane) as a prior z_n ~ N(h_n, sigma^2);
  // sigma 0 = off. Constrains what one source loop in a plane cannot (fig8a).
  std::vector<double> mic_heights_m;
  double height_prior_sigma_m = 0.0;
  double speed_of_sound_mps = 340.0;
  double tdoa_sigma_s = 0.333e-3;   // used where the input gives no per-row sigma
  double random_walk_sigma_m = 0.333;       // planar/3d: source random-walk prior
  double random_walk_sigma_rad = 50.0 * M_PI / 180.0;  // linear: source-angle random walk
  double linear_spacing_m = 0.05;   // linear: distance between adjacent microphones
  // 3d: the source moved in the plane z = 0 of the gauge frame (the plane of mic 1, the x mic
  // and the plane mic), e.g. carried around a table the array partly stands on.
  bool sources_in_gauge_plane = false;
  // Gauge microphones, 1-based as in the thesis (0 = choose automatically).
  int gauge_x_mic = 0;
  int gauge_plane_mic = 0;
  int gauge_z_mic = 0;
  // Multi-start random initialisation.
  int num_starts = 6;
  double init_extent_m = 1.5;       // mics and sources drawn uniformly in [-e, e]^D
  int64_t seed = 1;
  // Stop trying new starts once two starts have reached the same lowest cost (relative
  // difference below this): that minimum has been found twice from random points.
  double agree_tolerance = 1e-3;
  int max_iterations = 50;          // Table 3.1
  double parameter_tolerance = 1e-4;  // Table 3.1 epsilon for delta x (relative, Ceres)
  double function_tolerance = 1e-10;
  std::string loss = "huber";       // none | huber | cauchy (on whitened TDOA residuals)
  double loss_scale = 3.0;          // in sigmas
  bool compute_covariance = true;
  double max_position_std_m = 0.5;  // refuse: a mic this uncertain is not calibrated
  double max_offset_std_s = 0.05;
  int num_threads = 1;
  bool verbose = false;             // per-start progress lines on stderr
  // Known array motion, static source (CalibrateWithArrayPoses): the source's height above
  // the array's microphones (known: the TDOAs of an array moving in a horizontal plane see
  // only |dz|, and barely), the smallest span of the source bearing in the array frame that
  // separates the clocks from the geometry, and the source-position grid of the first guess.
  double static_source_dz_m = 0.0;
  // Optional prior on the static source's (x, y) in the pose frame (e.g. taped from the
  // robot's start pose): turning in place sees the source's range only through the parallax
  // of the array's offset from the turning centre, and a wrong range trades off with a clock
  // pattern along a line array. Empty = no prior.
  std::vector<double> static_source_prior_xy_m;
  double static_source_prior_sigma_m = 0.05;
  double min_bearing_span_deg = 60.0;
  double grid_margin_m = 3.0;       // grid over the array path's bounding box +- this
  double grid_step_m = 0.1;
  // Pose uncertainty (odometry): the array poses become unknowns of a pose graph whose edges
  // are the given relative motions between consecutive emissions with the odometry's random-
  // walk noise (std after 1 m driven / 1 rad turned / heading per metre). All 0 = poses exact.
  double pose_trans_sigma_per_sqrt_m = 0.0;
  double pose_rot_sigma_per_sqrt_rad = 0.0;
  double pose_rot_sigma_per_sqrt_m = 0.0;

  template <class V>
  void Visit(V& v) {
    v("geometry", geometry, "planar, 3d or linear (known spacing: offsets and drift only)",
      OneOf({"planar", "3d", "linear"}));
    v("synchronous", synchronous, "synchronous array: estimate positions only (tau = delta = 0)");
    v("estimate_drift", estimate_drift, "estimate clock drift (false: thesis Fig. 3.13 ablation)");
    v("mic_heights_m", mic_heights_m, "3d: known mic heights in the gauge frame (prior)");
    v("height_prior_sigma_m", height_prior_sigma_m, "3d: std of the height prior (0 = off)");
    v("known_positions", known_positions,
      "microphone positions known (--nominal): estimate offsets, drifts and sources only");
    v("speed_of_sound_mps", speed_of_sound_mps, "speed of sound c", Positive());
    v("tdoa_sigma_s", tdoa_sigma_s, "TDOA noise std where the input has none", Positive());
    v("random_walk_sigma_m", random_walk_sigma_m, "source random-walk prior std (planar/3d)",
      Positive());
    v("random_walk_sigma_rad", random_walk_sigma_rad, "source-angle random-walk std (linear)",
      Positive());
    v("linear_spacing_m", linear_spacing_m, "linear: known adjacent-microphone spacing",
      Positive());
    v("sources_in_gauge_plane", sources_in_gauge_plane,
      "3d: the source moved in the z = 0 plane of mic 1, the x mic and the plane mic");
    v("gauge_x_mic", gauge_x_mic, "1-based mic on +x (0: automatic)");
    v("gauge_plane_mic", gauge_plane_mic, "1-based mic with y > 0 (3d: and z = 0) (0: automatic)");
    v("gauge_z_mic", gauge_z_mic, "3d: 1-based mic with z > 0 (0: automatic)");
    v("num_starts", num_starts, "random initialisations tried (best cost kept)", AtLeast(1));
    v("init_extent_m", init_extent_m, "random initialisation box half-size", Positive());
    v("seed", seed, "random seed of the initialisations");
    v("agree_tolerance", agree_tolerance,
      "stop once two starts reach the same lowest cost (relative)", NonNegative());
    v("max_iterations", max_iterations, "solver iterations per start", AtLeast(1));
    v("parameter_tolerance", parameter_tolerance, "relative step size that ends a start",
      Positive());
    v("function_tolerance", function_tolerance, "relative cost decrease that ends a start",
      Positive());
    v("loss", loss, "robust loss on TDOA residuals: none, huber or cauchy",
      OneOf({"none", "huber", "cauchy"}));
    v("loss_scale", loss_scale, "robust loss scale in TDOA sigmas", Positive());
    v("compute_covariance", compute_covariance, "marginal covariances of every estimate");
    v("max_position_std_m", max_position_std_m, "refuse when a mic position std exceeds this",
      Positive());
    v("max_offset_std_s", max_offset_std_s, "refuse when a start-offset std exceeds this",
      Positive());
    v("num_threads", num_threads, "Ceres threads", AtLeast(1));
    v("verbose", verbose, "progress per start on stderr");
    v("static_source_dz_m", static_source_dz_m,
      "known array poses: height of the static source above the microphones (m)");
    v("static_source_prior_xy_m", static_source_prior_xy_m,
      "known array poses: prior on the static source's x, y in the pose frame (empty = none)");
    v("static_source_prior_sigma_m", static_source_prior_sigma_m,
      "known array poses: std of that prior", Positive());
    v("min_bearing_span_deg", min_bearing_span_deg,
      "known array poses: refuse when the source bearing in the array frame spans less",
      InRange(0, 180));
    v("grid_margin_m", grid_margin_m, "known array poses: source search grid beyond the path",
      NonNegative());
    v("grid_step_m", grid_step_m, "known array poses: source search grid step", Positive());
    v("pose_trans_sigma_per_sqrt_m", pose_trans_sigma_per_sqrt_m,
      "known array poses: odometry distance error std after 1 m (0 with the others: exact)",
      NonNegative());
    v("pose_rot_sigma_per_sqrt_rad", pose_rot_sigma_per_sqrt_rad,
      "known array poses: odometry heading error std after turning 1 rad", NonNegative());
    v("pose_rot_sigma_per_sqrt_m", pose_rot_sigma_per_sqrt_m,
      "known array poses: odometry heading error std after driving 1 m", NonNegative());
  }
  void Validate(common::Validator& check) const;
  int dim() const { return geometry == "3d" ? 3 : 2; }
};

// The TDOA data of one recording. tdoa_s(k, n - 2) is z_n(k), n = 2..N; NaN = missing.
struct TdoaData {
  int num_mics = 0;
  std::vector<double> times_s;  // t_k of each emission (seconds since the reference start)
  Eigen::MatrixXd tdoa_s;       // K x (N - 1)
  std::vector<double> sigma_s;  // per emission TDOA std, or empty (use the options')
  // Absolute time (us, the recording's clock: LCM utime) of each emission, or empty when not
  // known (WAV input); used to look up the array pose of each emission.
  std::vector<int64_t> utimes;
  // Optional per-edge motion prior (edge k links k and k+1): displacement and std; empty =
  // the zero-mean random walk of the options.
  std::vector<Eigen::Vector3d> motion_m;
  std::vector<Eigen::Vector3d> motion_sigma_m;
  int num_emissions() const { return static_cast<int>(tdoa_s.rows()); }
};

// Refusal: the data cannot determine the requested unknowns; `what()` says which and why.
class UnobservableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct StartSummary {
  int start = 0;
  double final_cost = 0;
  int iterations = 0;
  double normalised_rms = 0;
  bool converged = false;
  int num_residuals = 0, num_parameters = 0;  // effective (free) parameters
};

struct CalibrationResult {
  int dim = 2;
  std::vector<Eigen::Vector3d> mic_positions_m;  // z = 0 in 2D; linear: known positions
  std::vector<double> start_offsets_s;           // tau_n, tau_1 = 0
  std::vector<double> clock_drift;               // delta_n (s per s), delta_1 = 0
  std::vector<Eigen::Vector3d> source_positions_m;  // planar/3d
  std::vector<double> source_angles_rad;            // linear
  // Marginal covariances (ambient coordinates; fixed gauge components are 0).
  std::vector<Eigen::Matrix3d> mic_position_cov;
  std::vector<Eigen::Matrix2d> clock_cov;  // (tau [s], delta [s/s])
  std::vector<Eigen::Matrix3d> source_cov;
  bool has_covariance = false;
  // TDOA residuals z_hat - z (seconds), K x (N-1), NaN where the input was missing.
  Eigen::MatrixXd tdoa_residual_s;
  double residual_rms_s = 0, residual_std_s = 0, residual_max_abs_s = 0;
  double final_cost = 0;
  int best_start = 0;
  int iterations = 0;         // of the best start
  int total_iterations = 0;   // over all starts tried
  double solve_time_s = 0;    // all starts
  double covariance_time_s = 0;
  std::vector<StartSummary> starts;
  // The best start met the solver's tolerances. False: it stopped at max_iterations (or failed);
  // the estimate and its covariance describe where it stopped, not a minimum, and are not to be
  // trusted (a warning says so, and sarmap-mic-calibrate exits 4).
  bool converged = true;
  // A-posteriori variance factor (at least 1): the sum of squared weighted residuals over the
  // degrees of freedom (residuals - free parameters). The covariances are scaled by it, so
  // residuals larger than the stated TDOA sigma widen the reported std.
  double variance_factor = 1;
  std::vector<std::string> warnings;
  int gauge_ref = 1, gauge_x = 0, gauge_plane = 0, gauge_z = 0;  // 1-based
  // Known array poses: span of the static source's bearing in the array frame (degrees;
  // folded to 0..180 for a collinear array), -1 otherwise.
  double bearing_span_deg = -1;
  // Last emission time (s): the clock model is extrapolated beyond it (see ClockStdAt).
  double recording_end_s = 0;
};

// Worst standard deviation over the microphones of the clock correction tau_n + t delta_n at
// reference time t (s), from the marginal covariances (0 without them): how far the
// calibration can be trusted at, e.g., twice the recording's length.
double ClockStdAt(const CalibrationResult& result, double t_s);

// An initial guess for the first start (the others stay random): e.g. nominal positions.
// Empty vectors = not given (offsets/drifts then come from a line fit, sources random).
struct InitialGuess {
  std::vector<Eigen::Vector3d> mic_positions_m;  // N, in the gauge frame
  std::vector<double> start_offsets_s, clock_drift;  // N
  std::vector<Eigen::Vector3d> source_positions_m;   // K
  std::vector<double> source_angles_rad;             // K (linear)
};

// Checks what the data can determine (refuses with UnobservableError), solves, fixes the
// gauge signs, computes covariances. Throws std::invalid_argument on malformed input.
// residual_rms_s, residual_std_s and residual_max_abs_s over the finite tdoa_residual_s.
void SetResidualStatistics(CalibrationResult* result);
// After the solve (tdoa_residual_s and starts set): `converged` from the best start, with a
// warning when it did not converge, and `variance_factor` from the residuals (sigma per emission
// from data.sigma_s, else options.tdoa_sigma_s).
void AssessSolve(const TdoaData& data, const SolverOptions& options, CalibrationResult* result);

CalibrationResult Calibrate(const TdoaData& data, const SolverOptions& options,
                            const InitialGuess* guess = nullptr);

// The rigid motion (plus mirror) that puts known positions (measured/nominal, any frame) into
// the calibration gauge frame: mic 1 at the origin, mic x on +x, (3d) mic plane in z = 0 with
// y > 0 and mic z with z > 0; (planar) mic plane with y > 0. Apply it to the microphones
// and to any source truth before comparing with an estimate.
struct GaugeTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // may include a mirror
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return rotation * (p - origin); }
};
GaugeTransform GaugeFrameOf(const std::vector<Eigen::Vector3d>& positions, int dim, int x_mic,
                            int plane_mic, int z_mic);
std::vector<Eigen::Vector3d> ToGaugeFrame(const std::vector<Eigen::Vector3d>& positions,
                                          int dim, int x_mic, int plane_mic, int z_mic);

// Gauge microphones (1-based). With nominal positions: x = the mic farthest from mic 1,
// plane = farthest from the mic1-x line, z = farthest from that plane; without: 2, 3, 4.
// Entries already > 0 are kept.
void ChooseGauge(int num_mics, int dim, const std::vector<Eigen::Vector3d>& nominal, int* x_mic,
                 int* plane_mic, int* z_mic);

// --- Known array motion, static source -------------------------------------------------
// A robot carries the array and turns in place or drives (poses from odometry or SLAM) while
// one source stands still. Microphone n (known position m_n in the array frame) is at
// m_n(k) = world_from_array_k * m_n at emission k, and
//
//   z_n(k) = (|m_n(k) - s| - |m_1(k) - s|) / c + tau_n + t_k delta_n
//
// with ONE unknown source position s = (x, y, z_array + static_source_dz_m) in the world frame
// and the clocks (tau_n, delta_n), n >= 2. Why: with the microphones on one line and an
// unknown source path, an offset pattern linear along the line (tau_n = a x_n) is exactly a
// change of every source bearing (cos beta_k -> cos beta_k - a c, eq. 3.49), and a drift
// pattern the same growing with time: unobservable however long the recording. With known
// headings the bearing at k is fixed by the one point s and the pose, so such a pattern
// would have to be one shift of cos beta at many different bearings, which no single s
// gives: tau and delta become observable once the bearing in the array frame spans enough.
// Poses from odometry drift: with options.pose_*_sigma_* > 0 the array poses (x, y, yaw) are
// unknowns too, linked by the given relative motions between consecutive emissions with the
// odometry's random-walk noise (a pose graph; the first pose is held as the gauge). A clock
// pattern would need heading corrections following 1 / sin(bearing), which the random walk
// does not allow, so the confound stays broken while the odometry drift is taken out.
// Solve: a grid over s (clocks by linear least squares at each node, truncated cost), then
// Ceres (SPARSE_NORMAL_CHOLESKY, SuiteSparse, robust loss) from the best grid nodes; marginal
// covariances of s and every (tau, delta). Refuses (UnobservableError) when the array never
// moved, when the bearing span is below options.min_bearing_span_deg (the confound above),
// or when the covariance is rank deficient / too wide. result.source_positions_m = {s}.
CalibrationResult CalibrateWithArrayPoses(const TdoaData& data,
                                          const std::vector<Eigen::Isometry3d>& world_from_array,
                                          const std::vector<Eigen::Vector3d>& mic_positions_m,
                                          const SolverOptions& options);

namespace internal_testing {
// Compares the analytic TDOA cost with the autodiff functor at random points (dim 2 or 3).
bool CheckTdoaJacobian(int dim);
}  // namespace internal_testing

}  // namespace mic_calibrate
}  // namespace sarmap
