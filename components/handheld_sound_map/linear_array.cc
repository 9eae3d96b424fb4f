#include "handheld_sound_map/linear_array.h"

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>
#include <ceres/jet.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

#include "common/logging.h"
#include "handheld_sound_map/linear_array_costs.h"
#include "sound_map/joint_solver_options.h"

namespace sarmap {
namespace sound_map {

namespace {

using linear_costs::BetaCost;
using linear_costs::BetaFromKeyframe;
using linear_costs::Odometry6Cost;
using linear_costs::Pose6;
using linear_costs::WrapAngle;

// beta of s = (beta, gamma, rho) seen from `pose`, in the scaled form that stays finite
// as rho -> 0:  d = rho (o - t) + R_axis u(beta, gamma),  d_l = R' d,
// beta_hat = atan2(d_l.y, |d_l.xz|)   (5.13, 5.19, 5.20).
template <class T>
T PredictBeta(const ArrayAxis& axis, const Eigen::Isometry3d& pose, const T* s) {
  using std::atan2;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Eigen::Matrix<T, 3, 1> u(cos(s[0]) * cos(s[1]), sin(s[0]), cos(s[0]) * sin(s[1]));
  const Eigen::Matrix<T, 3, 1> d = s[2] * (axis.origin - pose.translation()).cast<T>() + axis.rotation().cast<T>() * u;
  const Eigen::Matrix<T, 3, 1> dl = pose.linear().transpose().cast<T>() * d;
  return atan2(dl[1], sqrt(dl[0] * dl[0] + dl[2] * dl[2]));
}

}  // namespace

ArrayAxis ArrayAxis::FromPose(const Eigen::Isometry3d& pose) {
  ArrayAxis a;
  a.origin = pose.translation();
  const Eigen::Vector3d y = pose.linear().col(1);
  a.theta = std::atan2(y.y(), y.x());
  a.phi = std::atan2(y.z(), std::hypot(y.x(), y.y()));
  return a;
}

Eigen::Matrix3d ArrayAxis::rotation() const {
  return (Eigen::AngleAxisd(theta - M_PI / 2, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d HypothesisPoint(const ArrayAxis& axis, const Eigen::Vector3d& s) {
  const Eigen::Vector3d u(std::cos(s[0]) * std::cos(s[1]), std::sin(s[0]), std::cos(s[0]) * std::sin(s[1]));
  return axis.origin + axis.rotation() * u / std::max(s[2], 1e-6);
}

double LinearArrayBeta(const Eigen::Isometry3d& pose, const Eigen::Vector3d& p) {
  const Eigen::Vector3d l = pose.inverse() * p;
  return std::atan2(l.y(), std::hypot(l.x(), l.z()));
}

MultiHypothesisSource::MultiHypothesisSource(const MultiHypothesisOptions& o, const Eigen::Isometry3d& pose,
                                             double beta, double beta_variance)
    : options_(o), axis_(ArrayAxis::FromPose(pose)) {
  const int n = std::max(1, o.num_hypotheses);
  const double rho0 = 1.0 / (3.0 * o.min_distance_m);
  for (int i = 1; i <= n; ++i) {
    Hypothesis h;
    h.s = Eigen::Vector3d(beta, 2 * M_PI * i / n - M_PI, rho0);  // (5.10-5.11)
    h.p = Eigen::Vector3d(beta_variance, std::pow(M_PI / n, 2), rho0 * rho0).asDiagonal();  // (5.12)
    hypotheses_.push_back(h);
  }
}

void MultiHypothesisSource::Update(const Eigen::Isometry3d& pose, double beta, double var) {
  using J3 = ceres::Jet<double, 3>;
  for (Hypothesis& h : hypotheses_) {
    if (!h.alive) continue;
    J3 s[3] = {J3(h.s[0], 0), J3(h.s[1], 1), J3(h.s[2], 2)};
    const J3 zh = PredictBeta(axis_, pose, s);
    const Eigen::RowVector3d hj = zh.v.transpose();
    const double nu = WrapAngle(beta - zh.a);
    const double hph = hj * h.p * hj.transpose();
    const double sv = hph + var;
    // (5.21-5.22): the thesis prints S = H P H'; the innovation covariance adds Q.
    h.chi2_sum += nu * nu / (options_.chi2_with_noise ? sv : std::max(hph, 1e-12));
    ++h.updates;
    const Eigen::Vector3d k = h.p * hj.transpose() / sv;  // (5.16)
    h.s += k * nu;                                         // (5.17)
    h.s[1] = WrapAngle(h.s[1]);
    h.s[2] = std::max(h.s[2], 1e-3);
    h.p = (Eigen::Matrix3d::Identity() - k * hj) * h.p;    // (5.18)
    h.p = 0.5 * (h.p + h.p.transpose()).eval();
    // Linearity index of the inverse depth (5.23-5.27, Civera et al.):
    //   L = 4 sigma_d |cos alpha| / |h|,  sigma_d = sigma_rho / rho^2,
    // h from the current sensor to the point, alpha between h and the anchor ray m.
    const Eigen::Vector3d p = HypothesisPoint(axis_, h.s);
    const Eigen::Vector3d hv = p - (options_.linearity_from_anchor ? axis_.origin : pose.translation());
    const Eigen::Vector3d m = (p - axis_.origin).normalized();
    const double sigma_d = std::sqrt(std::max(h.p(2, 2), 0.0)) / (h.s[2] * h.s[2]);
    h.linearity = 4 * sigma_d * std::abs(m.dot(hv.normalized())) / std::max(hv.norm(), 1e-6);
  }
  // Prune hypotheses whose mean chi-square is too large; keep the best one alive.
  int best = -1;
  double best_mean = 1e300;
  for (size_t i = 0; i < hypotheses_.size(); ++i) {
    const Hypothesis& h = hypotheses_[i];
    if (!h.alive) continue;
    const double mean = h.chi2_sum / std::max(1, h.updates);
    if (mean < best_mean) best_mean = mean, best = static_cast<int>(i);
  }
  for (size_t i = 0; i < hypotheses_.size(); ++i) {
    Hypothesis& h = hypotheses_[i];
    if (!h.alive || static_cast<int>(i) == best) continue;
    if (h.updates < options_.prune_min_observations) continue;
    // Mean chi-square too large (5.22): either above the fixed bound, or, over n updates,
    // above the (1 - alpha) quantile of chi2(n) / n (Wilson-Hilferty approximation).
    const double n = h.updates;
    const double wh = 1 - 2 / (9 * n) + options_.prune_z * std::sqrt(2 / (9 * n));
    const double quantile_mean = wh * wh * wh;
    const double mean = h.chi2_sum / n;
    if (mean > options_.prune_mean_chi2 || (options_.prune_z > 0 && mean > quantile_mean)) h.alive = false;
  }
  // Relative pruning (our addition; a multi-hypothesis tracker's likelihood-ratio test):
  // a hypothesis whose summed chi-square exceeds the best one's by more than
  // relative_prune_chi2 is (exp(-d/2)) far less likely.
  if (options_.relative_prune_chi2 > 0 && best >= 0 &&
      hypotheses_[best].updates >= options_.relative_prune_min_observations) {
    const double best_sum = hypotheses_[best].chi2_sum;
    for (size_t i = 0; i < hypotheses_.size(); ++i) {
      Hypothesis& h = hypotheses_[i];
      if (h.alive && static_cast<int>(i) != best && h.chi2_sum - best_sum > options_.relative_prune_chi2)
        h.alive = false;
    }
  }
  // Converged to separate places: drop the clearly less likely ones.
  if (AllLinear() && !Clustered()) {
    for (size_t i = 0; i < hypotheses_.size(); ++i) {
      Hypothesis& h = hypotheses_[i];
      if (h.alive && static_cast<int>(i) != best &&
          h.chi2_sum / h.updates > options_.relative_prune * best_mean)
        h.alive = false;
    }
  }
}

int MultiHypothesisSource::alive() const {
  int n = 0;
  for (const auto& h : hypotheses_) n += h.alive;
  return n;
}

bool MultiHypothesisSource::AllLinear() const {
  for (const auto& h : hypotheses_) {
    if (!h.alive) continue;
    if (h.updates < options_.min_observations || h.linearity > options_.linearity_threshold) return false;
  }
  return true;
}

bool MultiHypothesisSource::Clustered() const {
  const Eigen::Vector3d mean = MeanPoint();
  for (const auto& h : hypotheses_)
    if (h.alive && (HypothesisPoint(axis_, h.s) - mean).norm() > options_.cluster_radius_m) return false;
  return true;
}

bool MultiHypothesisSource::ClusteredUpToMirror() const {
  std::vector<Eigen::Vector3d> pts;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& h : hypotheses_) {
    if (!h.alive) continue;
    Eigen::Vector3d p = HypothesisPoint(axis_, h.s);
    p.z() = axis_.origin.z() + std::abs(p.z() - axis_.origin.z());
    pts.push_back(p);
    mean += p;
  }
  if (pts.empty()) return false;
  mean /= pts.size();
  for (const auto& p : pts)
    if ((p - mean).norm() > options_.cluster_radius_m) return false;
  return true;
}

bool MultiHypothesisSource::converged() const {
  return AllLinear() && (Clustered() || (options_.converge_mirror_pairs && ClusteredUpToMirror())) && !Failed();
}

bool MultiHypothesisSource::Failed() const {
  bool any = false;
  for (const auto& h : hypotheses_) {
    if (!h.alive) continue;
    if (h.updates < options_.prune_min_observations ||
        h.chi2_sum / h.updates <= options_.prune_mean_chi2)
      return false;
    any = true;
  }
  return any;
}

Eigen::Vector3d MultiHypothesisSource::MeanPoint() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& h : hypotheses_) {
    if (!h.alive) continue;
    sum += HypothesisPoint(axis_, h.s);
    ++n;
  }
  return n ? Eigen::Vector3d(sum / n) : axis_.origin;
}

double MultiHypothesisSource::chi2(const Eigen::Isometry3d& pose, double beta, double var) const {
  using J3 = ceres::Jet<double, 3>;
  double best = 1e300;
  for (const Hypothesis& h : hypotheses_) {
    if (!h.alive) continue;
    J3 s[3] = {J3(h.s[0], 0), J3(h.s[1], 1), J3(h.s[2], 2)};
    const J3 zh = PredictBeta(axis_, pose, s);
    const Eigen::RowVector3d hj = zh.v.transpose();
    const double nu = WrapAngle(beta - zh.a);
    best = std::min(best, nu * nu / (hj * h.p * hj.transpose() + var));
  }
  return best;
}

// ------------------------------------------------------------------ simulation

double SimulatedDoaSigma(double true_beta_rad) {
  const double f = std::min(1.0, std::abs(true_beta_rad) / (M_PI / 2));
  return (10.0 + 10.0 * f * f) * M_PI / 180;
}

namespace {

// A dense path (1 cm) with, per point, a yaw to face (NaN: face along the path).
struct PathBuilder {
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> yaw;
  double hold_yaw = NAN;  // while set, every new point faces this yaw (up/down at an arc)
  void Push(const Eigen::Vector3d& p, double y) {
    pts.push_back(p);
    yaw.push_back(y);
  }
  void LineTo(const Eigen::Vector3d& p) {
    const Eigen::Vector3d a = pts.back();
    const int n = std::max(1, static_cast<int>((p - a).norm() / 0.01));
    for (int i = 1; i <= n; ++i) Push(a + (p - a) * (static_cast<double>(i) / n), hold_yaw);
  }
  // Arc about c; the sensor faces the centre turned by `face_offset` (NaN: along the arc).
  void Arc(const Eigen::Vector2d& c, double r, double a0, double a1, double face_offset) {
    const double z = pts.back().z();
    const int n = std::max(1, static_cast<int>(std::abs(a1 - a0) * r / 0.01));
    for (int i = 1; i <= n; ++i) {
      const double a = a0 + (a1 - a0) * i / n;
      Push(Eigen::Vector3d(c.x() + r * std::cos(a), c.y() + r * std::sin(a), z),
           std::isnan(face_offset) ? hold_yaw : a + M_PI + face_offset);
    }
  }
  void UpDown(double h) {
    const Eigen::Vector3d b = pts.back();
    LineTo(b + Eigen::Vector3d(0, 0, h));
    LineTo(b - Eigen::Vector3d(0, 0, h));
    LineTo(b);
  }
};

std::vector<Eigen::Isometry3d> Resample(const PathBuilder& path, double step) {
  const std::vector<Eigen::Vector3d>& pts = path.pts;
  std::vector<Eigen::Isometry3d> poses;
  double yaw = 0, acc = 0;
  Eigen::Vector3d last = pts[0];
  auto emit = [&](const Eigen::Vector3d& p) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    t.translation() = p;
    poses.push_back(t);
  };
  emit(pts[0]);
  for (size_t i = 1; i < pts.size(); ++i) {
    const Eigen::Vector3d d = pts[i] - pts[i - 1];
    if (!std::isnan(path.yaw[i]))
      yaw = path.yaw[i];
    else if (std::hypot(d.x(), d.y()) > 1e-9)
      yaw = std::atan2(d.y(), d.x());
    acc += d.norm();
    if (acc >= step - 1e-9) {
      emit(pts[i]);
      acc = 0;
      last = pts[i];
    }
  }
  return poses;
}

}  // namespace

LinearSimData SimulateLinear(const LinearSimConfig& c) {
  LinearSimData d;
  d.config = c;
  std::mt19937_64 rng(c.seed);
  std::normal_distribution<double> n01(0, 1);
  std::uniform_real_distribution<double> u01(0, 1);
  PathBuilder path;
  path.Push(Eigen::Vector3d::Zero(), NAN);
  double size = 8.0;
  if (c.trajectory == 1) {
    // Per side of an 8 m square: 2 m, a quarter arc (radius 2 m) around the side's middle
    // on the outside, up and down, another quarter arc back to the side, 2 m.
    d.sources = {{4, 0, 1}, {4, 0, -1}, {4, 8, 1}, {4, 8, -1}, {8, 4, 1}, {8, 4, -1}, {0, 4, 1}, {0, 4, -1}};
    for (int side = 0; side < 4; ++side) {
      const double a = side * M_PI / 2;
      const Eigen::Vector2d dir(std::cos(a), std::sin(a)), left(-dir.y(), dir.x());
      const Eigen::Vector2d s = path.pts.back().head<2>();
      const Eigen::Vector2d centre = s + 4 * dir;
      path.LineTo(Eigen::Vector3d((s + 2 * dir).x(), (s + 2 * dir).y(), 0));
      const double a0 = std::atan2(-dir.y(), -dir.x());
      if (c.fixed_heading) {
        // The sensor keeps facing along the side while it side-steps round the source.
        path.hold_yaw = a;
        path.Arc(centre, 2.0, a0, a0 + M_PI / 2, NAN);
        path.UpDown(c.updown_m);
        path.Arc(centre, 2.0, a0 + M_PI / 2, a0 + M_PI, NAN);
        path.hold_yaw = NAN;
      } else {
        // On the arcs the sensor looks c.arc_face_offset_rad to the side of the source.
        path.Arc(centre, 2.0, a0, a0 + M_PI / 2, c.arc_face_offset_rad);
        path.hold_yaw = a0 + M_PI / 2 + M_PI + c.arc_face_offset_rad;
        path.UpDown(c.updown_m);
        path.hold_yaw = NAN;
        path.Arc(centre, 2.0, a0 + M_PI / 2, a0 + M_PI, c.arc_face_offset_rad);
      }
      path.LineTo(Eigen::Vector3d((s + 8 * dir).x(), (s + 8 * dir).y(), 0));
    }
  } else {
    // Per side of a 12 m square: 4 m, up and down, 4 m, up and down, 4 m; then the diagonal.
    size = 12.0;
    d.sources = {{4, 1, 0.5}, {8, 1, -0.5}, {11, 4, 0.5}, {11, 8, -0.5},
                 {8, 11, 0.5}, {4, 11, -0.5}, {1, 4, 0.5}, {1, 8, -0.5}};
    for (int side = 0; side < 4; ++side) {
      const double a = side * M_PI / 2;
      const Eigen::Vector2d dir(std::cos(a), std::sin(a));
      const Eigen::Vector2d s = path.pts.back().head<2>();
      for (int part = 1; part <= 3; ++part) {
        const Eigen::Vector2d p = s + 4.0 * part * dir;
        path.LineTo(Eigen::Vector3d(p.x(), p.y(), 0));
        if (part < 3) path.UpDown(c.updown_m);
      }
    }
    path.LineTo(Eigen::Vector3d(12, 12, 0));
  }
  d.truth = Resample(path, c.step_m);

  const double lo = -3, hi = size + 3;
  const int nl = static_cast<int>(c.landmark_density_per_m2 * (hi - lo) * (hi - lo));
  for (int i = 0; i < nl; ++i)
    d.landmarks.emplace_back(lo + (hi - lo) * u01(rng), lo + (hi - lo) * u01(rng), -1.5 + 3 * u01(rng));

  d.odometry.resize(d.truth.size(), Eigen::Isometry3d::Identity());
  for (size_t k = 1; k < d.truth.size(); ++k) {
    Eigen::Isometry3d rel = d.truth[k - 1].inverse() * d.truth[k];
    const Eigen::Vector3d dr(c.odo_sigma_rad * n01(rng), c.odo_sigma_rad * n01(rng), c.odo_sigma_rad * n01(rng));
    const Eigen::Vector3d dt(c.odo_sigma_m * n01(rng), c.odo_sigma_m * n01(rng), c.odo_sigma_m * n01(rng));
    Eigen::Isometry3d noise = Eigen::Isometry3d::Identity();
    if (dr.norm() > 0) noise.linear() = Eigen::AngleAxisd(dr.norm(), dr.normalized()).toRotationMatrix();
    noise.translation() = dt;
    d.odometry[k] = rel * noise;
  }
  d.landmark_obs.resize(d.truth.size());
  d.sound_obs.resize(d.truth.size());
  for (size_t k = 0; k < d.truth.size(); ++k) {
    const Eigen::Isometry3d inv = d.truth[k].inverse();
    for (size_t j = 0; j < d.landmarks.size(); ++j) {
      const Eigen::Vector3d l = inv * d.landmarks[j];
      const double r = l.norm();
      if (r > c.landmark_range_m || r < 0.2) continue;
      if (std::acos(std::clamp(l.x() / r, -1.0, 1.0)) > c.landmark_fov_rad) continue;
      const double az = std::atan2(l.y(), l.x()), el = std::atan2(l.z(), std::hypot(l.x(), l.y()));
      d.landmark_obs[k].push_back({static_cast<int64_t>(j),
                                   Eigen::Vector3d(r + c.landmark_sigma_m * n01(rng),
                                                   az + c.landmark_sigma_rad * n01(rng),
                                                   el + c.landmark_sigma_rad * n01(rng))});
    }
    for (size_t j = 0; j < d.sources.size(); ++j) {
      if ((d.sources[j] - d.truth[k].translation()).norm() > c.sound_range_m) continue;
      if (u01(rng) > c.heard_probability) continue;
      const double beta = LinearArrayBeta(d.truth[k], d.sources[j]);
      double raw;
      if (c.doa_generator) {
        double mean, var;
        c.doa_generator->Predict(beta, &mean, &var);
        raw = mean + c.doa_noise_scale * std::sqrt(var) * n01(rng);
      } else {
        raw = beta + c.doa_noise_scale * SimulatedDoaSigma(beta) * n01(rng);
      }
      if (c.doa_quantum_rad > 0) raw = c.doa_quantum_rad * std::round(raw / c.doa_quantum_rad);
      raw = std::clamp(raw, -M_PI / 2, M_PI / 2);
      d.sound_obs[k].push_back({static_cast<int64_t>(j), raw});
    }
  }
  return d;
}

void LoadDoaCalibrationCsv(const std::string& path, std::vector<double>* raw, std::vector<double>* truth) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot read DOA calibration file " + path);
  raw->clear();
  truth->clear();
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    double a, b;
    if (sscanf(line.c_str(), "%lf,%lf", &a, &b) != 2) continue;  // header
    raw->push_back(a * M_PI / 180);
    truth->push_back(b * M_PI / 180);
  }
  if (raw->size() < 3) throw std::invalid_argument("DOA calibration file " + path + " holds fewer than 3 pairs");
}

CalibratedDoa FitCalibratedDoa(const std::vector<double>& raw, const std::vector<double>& truth,
                               double quantum_rad) {
  CalibratedDoa c;
  // true -> raw: the forward model, the simulated sensor
  c.generator = GpDoaModel::Fit(truth, raw);
  c.sensor_model = std::make_shared<BayesInvertedDoaModel>(*c.generator, quantum_rad);
  c.thesis_model = GpDoaModel::Fit(raw, truth);  // raw -> true as the thesis does it (5.5-5.6)
  return c;
}

void SimulatedCalibration(uint64_t seed, std::vector<double>* raw, std::vector<double>* truth) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0, 1);
  raw->clear();
  truth->clear();
  for (int deg = -90; deg <= 90; deg += 5) {
    const double b = deg * M_PI / 180;
    for (int t = 0; t < 10; ++t) {
      truth->push_back(b);
      raw->push_back(std::clamp(b + SimulatedDoaSigma(b) * n01(rng), -M_PI / 2, M_PI / 2));
    }
  }
}

// ------------------------------------------------------------------ joint optimisation

namespace {

struct Landmark3Cost {
  Eigen::Vector3d z;
  double inv_sr, inv_sa;
  template <class T>
  bool operator()(const T* q_, const T* t_, const T* v_, T* r) const {
    using std::atan2;
    using std::sqrt;
    Eigen::Map<const Eigen::Quaternion<T>> q(q_);
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_), v(v_);
    const Eigen::Matrix<T, 3, 1> l = q.conjugate() * (v - t);
    const T xy = sqrt(l[0] * l[0] + l[1] * l[1]);
    r[0] = (sqrt(l.squaredNorm()) - T(z[0])) * T(inv_sr);
    r[1] = WrapAngle(T(atan2(l[1], l[0]) - T(z[1]))) * T(inv_sa);
    r[2] = (atan2(l[2], xy) - T(z[2])) * T(inv_sa);
    return true;
  }
};

// The forward model's mean g(beta) tabulated for Ceres: cubic interpolation works on Jets.
class ForwardTable {
 public:
  explicit ForwardTable(const DoaSensorModel& forward) : g_(kN), s2_(kN) {
    for (int i = 0; i < kN; ++i) forward.Predict(Beta(i), &g_[i], &s2_[i]);
    grid_ = std::make_unique<ceres::Grid1D<double>>(g_.data(), 0, kN);
    interp_ = std::make_unique<ceres::CubicInterpolator<ceres::Grid1D<double>>>(*grid_);
  }
  template <class T>
  T Mean(const T& beta) const {
    T g;
    interp_->Evaluate((beta + T(M_PI / 2)) / T(kStep), &g);
    return g;
  }
  double Variance(double beta) const {
    const int i = std::clamp(static_cast<int>(std::lround((beta + M_PI / 2) / kStep)), 0, kN - 1);
    return s2_[i];
  }

 private:
  static constexpr int kN = 721;
  static constexpr double kStep = M_PI / (kN - 1);
  static double Beta(int i) { return -M_PI / 2 + i * kStep; }
  std::vector<double> g_, s2_;
  std::unique_ptr<ceres::Grid1D<double>> grid_;
  std::unique_ptr<ceres::CubicInterpolator<ceres::Grid1D<double>>> interp_;
};

// The same observation in the DOA method's own angle: e = (raw - g(beta)) / s, with g the
// forward model's mean and s^2 its variance plus the grid's q^2/12. Unlike BetaCost it needs
// no inverse of g, which is flat and folds back near endfire, and it stays unbiased where
// a corrected angle is not (a regression of the truth on noisy raw angles flattens g^-1).
struct RawBetaCost {
  const ForwardTable* table;
  double raw, inv_sigma;
  template <class T>
  bool operator()(const T* q, const T* t, const T* p, T* r) const {
    r[0] = (T(raw) - table->Mean(BetaFromKeyframe(q, t, p))) * T(inv_sigma);
    return true;
  }
};

struct SourceTrack {
  std::unique_ptr<MultiHypothesisSource> mh;
  bool converged = false;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  struct Obs {
    int k;
    double beta, var;  // corrected by the sensor model
    double raw;
  };
  std::vector<Obs> obs;
};

class Mapper {
 public:
  Mapper(const LinearSimData& d, const LinearMapperOptions& o) : d_(d), o_(o) {
    if (o_.forward_model) forward_ = std::make_unique<ForwardTable>(*o_.forward_model);
  }

  LinearRunResult Run() {
    LinearRunResult res;
    const auto t0 = std::chrono::steady_clock::now();
    const size_t n = d_.truth.size();
    int last_full = -1000;
    for (size_t k = 0; k < n; ++k) {
      poses_.push_back(k == 0 || o_.oracle_poses ? Pose6::From(d_.truth[k])
                                                 : Pose6::From(poses_.back().iso() * d_.odometry[k]));
      bool loop = false;
      for (const auto& o : d_.landmark_obs[k]) {
        auto it = last_seen_.find(o.id);
        if (it != last_seen_.end() && static_cast<int>(k) - it->second > o_.loop_gap_keyframes) loop = true;
        last_seen_[o.id] = static_cast<int>(k);
        if (!landmarks_.count(o.id)) {
          const Eigen::Vector3d l(o.z[0] * std::cos(o.z[2]) * std::cos(o.z[1]),
                                  o.z[0] * std::cos(o.z[2]) * std::sin(o.z[1]), o.z[0] * std::sin(o.z[2]));
          landmarks_[o.id] = poses_.back().iso() * l;
        }
        lm_obs_[o.id].push_back({static_cast<int>(k), o.z});
      }
      // Converged sources heard now join this keyframe's optimisation.
      for (const auto& s : d_.sound_obs[k]) {
        SourceTrack& tr = tracks_[s.source];
        double beta, var;
        o_.sensor_model->Predict(s.raw_beta, &beta, &var);
        tr.obs.push_back({static_cast<int>(k), beta, var, s.raw_beta});
      }
      if (k > 0) {
        if (loop && static_cast<int>(k) - last_full > o_.loop_gap_keyframes / 2) {
          Optimise(0, static_cast<int>(k));
          last_full = static_cast<int>(k);
          ++res.full_optimisations;
        } else {
          Optimise(std::max(1, static_cast<int>(k) - o_.window_keyframes + 1), static_cast<int>(k));
        }
      }
      // Multi-hypothesis initialisation of the sources heard now, from this keyframe's pose.
      const Eigen::Isometry3d pose = poses_.back().iso();
      for (const auto& s : d_.sound_obs[k]) {
        SourceTrack& tr = tracks_[s.source];
        if (tr.converged) continue;
        const auto& ob = tr.obs.back();
        if (!tr.mh) {
          tr.mh = NewCone(pose, ob);
          if (o_.oracle_init) {
            tr.converged = true;
            tr.point = d_.sources[s.source];
          }
          continue;
        }
        tr.mh->Update(pose, ob.beta, ob.var);
        if (tr.mh->Failed()) {  // start the cone again from this DOA
          tr.mh = NewCone(pose, ob);
          ++res.restarted_sources;
          continue;
        }
        if (tr.mh->converged()) {
          tr.converged = true;
          tr.point = tr.mh->MeanPoint();
          if (o_.mirror_check) MirrorCheck(&tr);
        }
      }
    }
    Optimise(0, static_cast<int>(n) - 1);  // final full optimisation (the loop is closed)
    if (o_.mirror_check) {
      bool flipped = false;
      for (auto& kv : tracks_)
        if (kv.second.converged) flipped |= MirrorCheck(&kv.second);
      if (flipped) Optimise(0, static_cast<int>(n) - 1);
    }
    if (common::GetLogLevel() == common::LogLevel::DEBUG) {
      for (auto& kv : tracks_) {
        const SourceTrack& tr = kv.second;
        fprintf(stderr, "source %ld obs %zu converged %d", static_cast<long>(kv.first), tr.obs.size(), tr.converged);
        if (tr.mh) {
          fprintf(stderr, " alive %d linear %d clustered %d |", tr.mh->alive(), tr.mh->AllLinear(), tr.mh->Clustered());
          for (const auto& h : tr.mh->hypotheses())
            if (h.alive) fprintf(stderr, " (L %.2f n %d chi %.2f)", h.linearity, h.updates, h.chi2_sum / std::max(1, h.updates));
        }
        fprintf(stderr, " err %.3f\n", (tr.point - d_.sources[kv.first]).norm());
      }
      for (size_t k = 0; k < n; k += 20) {
        const Eigen::Isometry3d e = d_.truth[k].inverse() * poses_[k].iso();
        fprintf(stderr, "pose %zu: %zu landmark obs, error %.3f m %.2f deg\n", k, d_.landmark_obs[k].size(),
                e.translation().norm(), Eigen::AngleAxisd(e.linear()).angle() * 180 / M_PI);
      }
      const Eigen::Vector3d e = poses_.back().t - d_.truth.back().translation();
      fprintf(stderr, "final pose error %.3f m, %zu keyframes\n", e.norm(), n);
    }
    ++res.full_optimisations;
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double sum2 = 0;
    res.estimates.assign(d_.sources.size(), Eigen::Vector3d::Constant(NAN));
    res.source_converged.assign(d_.sources.size(), false);
    res.errors_m.assign(d_.sources.size(), NAN);
    for (auto& kv : tracks_) {
      if (!kv.second.converged) continue;
      res.estimates[kv.first] = kv.second.point;
      res.source_converged[kv.first] = true;
      res.errors_m[kv.first] = (kv.second.point - d_.sources[kv.first]).norm();
      sum2 += (kv.second.point - d_.sources[kv.first]).squaredNorm();
      ++res.converged;
    }
    res.rms_m = res.converged ? std::sqrt(sum2 / res.converged) : 0;
    res.axis_rms_m = res.rms_m / std::sqrt(3.0);
    double pt2 = 0, pr2 = 0;
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Isometry3d e = d_.truth[k].inverse() * poses_[k].iso();
      pt2 += e.translation().squaredNorm();
      pr2 += std::pow(Eigen::AngleAxisd(e.linear()).angle(), 2);
    }
    res.pose_rms_m = std::sqrt(pt2 / n);
    res.pose_rms_rad = std::sqrt(pr2 / n);
    res.floor_rms_m = FloorRms();
    res.convergence_rate = static_cast<double>(res.converged) / d_.sources.size();
    int correct = 0;
    for (size_t j = 0; j < d_.sources.size(); ++j)
      correct += res.source_converged[j] && (res.estimates[j] - d_.sources[j]).norm() < o_.converged_error_m;
    res.correct_convergence_rate = static_cast<double>(correct) / d_.sources.size();
    return res;
  }

 private:
  // N_h hypotheses on the cone of one DOA heard from `pose` (5.8-5.12).
  std::unique_ptr<MultiHypothesisSource> NewCone(const Eigen::Isometry3d& pose,
                                                 const SourceTrack::Obs& ob) const {
    MultiHypothesisOptions mo = o_.hypotheses;
    mo.num_hypotheses = o_.num_hypotheses;
    return std::make_unique<MultiHypothesisSource>(mo, pose, ob.beta, ob.var);
  }

  // The raw-angle residual of an observation. Its noise is taken at the corrected angle, not
  // at the estimate: a fixed weight keeps the problem a least-squares one.
  RawBetaCost RawCost(const SourceTrack::Obs& ob) const {
    const double var = forward_->Variance(ob.beta) + o_.doa_quantum_rad * o_.doa_quantum_rad / 12;
    return RawBetaCost{forward_.get(), ob.raw, 1.0 / std::sqrt(var)};
  }

  ceres::CostFunction* SoundCost(const SourceTrack::Obs& ob) const {
    if (forward_)
      return new ceres::AutoDiffCostFunction<RawBetaCost, 1, 4, 3, 3>(new RawBetaCost(RawCost(ob)));
    return new ceres::AutoDiffCostFunction<BetaCost, 1, 4, 3, 3>(
        new BetaCost{ob.beta, 1.0 / std::sqrt(ob.var)});
  }

  // Sum of squared sound residuals of a source at p over its observations so far.
  double SoundCostSum(const SourceTrack& tr, const Eigen::Vector3d& p) const {
    double sum = 0;
    for (const auto& ob : tr.obs) {
      if (ob.k >= static_cast<int>(poses_.size())) continue;
      const double* q = poses_[ob.k].q.coeffs().data();
      const double* t = poses_[ob.k].t.data();
      double r = 0;
      if (forward_)
        RawCost(ob)(q, t, p.data(), &r);
      else
        BetaCost{ob.beta, 1.0 / std::sqrt(ob.var)}(q, t, p.data(), &r);
      sum += r * r;
    }
    return sum;
  }

  // A level linear array hears p and its mirror image through the horizontal plane at its
  // own height at the same beta (the cone round the array axis is symmetric about every plane
  // that holds the axis). Only the poses off that plane tell the two apart, and a source
  // initialised on the wrong side stays there: the cost between them is a ridge. So compare
  // the cost at p and at its reflection through the mean height of the observing poses.
  // Returns true when the reflection is better and was taken.
  bool MirrorCheck(SourceTrack* tr) const {
    if (tr->obs.empty()) return false;
    double z = 0;
    int n = 0;
    for (const auto& ob : tr->obs)
      if (ob.k < static_cast<int>(poses_.size())) {
        z += poses_[ob.k].t.z();
        ++n;
      }
    if (n == 0) return false;
    z /= n;
    Eigen::Vector3d mirrored = tr->point;
    mirrored.z() = 2 * z - tr->point.z();
    if (SoundCostSum(*tr, mirrored) >= SoundCostSum(*tr, tr->point)) return false;
    tr->point = mirrored;
    return true;
  }

  // Per source: least squares of its DOAs from the true poses, started at the truth.
  double FloorRms() {
    double sum2 = 0;
    int n = 0;
    for (auto& kv : tracks_) {
      Eigen::Vector3d p = d_.sources[kv.first];
      std::vector<Pose6> truth;
      truth.reserve(kv.second.obs.size());
      for (const auto& ob : kv.second.obs) truth.push_back(Pose6::From(d_.truth[ob.k]));
      ceres::Problem::Options po;
      po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      ceres::Problem problem(po);
      ceres::EigenQuaternionManifold quat;
      for (size_t i = 0; i < truth.size(); ++i) {
        const auto& ob = kv.second.obs[i];
        problem.AddResidualBlock(SoundCost(ob), nullptr, truth[i].q.coeffs().data(),
                                 truth[i].t.data(), p.data());
        problem.SetManifold(truth[i].q.coeffs().data(), &quat);
        problem.SetParameterBlockConstant(truth[i].q.coeffs().data());
        problem.SetParameterBlockConstant(truth[i].t.data());
      }
      if (truth.empty()) continue;
      ceres::Solver::Options so;
      so.max_num_iterations = 50;
      so.logging_type = ceres::SILENT;
      ceres::Solver::Summary sum;
      ceres::Solve(so, &problem, &sum);
      sum2 += (p - d_.sources[kv.first]).squaredNorm();
      ++n;
    }
    return n ? std::sqrt(sum2 / n) : 0;
  }

  // Joint optimisation (5.29) over keyframes first..last (first == 0: everything, the first
  // pose held as gauge), the landmarks and converged sources they observe; observations
  // of those from older keyframes enter with the older poses held constant.
  void Optimise(int first, int last) {
    ceres::Problem::Options po;
    po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    ceres::EigenQuaternionManifold quat;
    std::set<int> used_poses;
    auto add_pose = [&](int k) {
      if (used_poses.insert(k).second) {
        problem.AddParameterBlock(poses_[k].q.coeffs().data(), 4, &quat);
        problem.AddParameterBlock(poses_[k].t.data(), 3);
        if (k < first || k == 0 || o_.oracle_poses) {
          problem.SetParameterBlockConstant(poses_[k].q.coeffs().data());
          problem.SetParameterBlockConstant(poses_[k].t.data());
        }
      }
    };
    const LinearSimConfig& c = d_.config;
    for (int k = std::max(1, first); k <= last; ++k) {
      add_pose(k - 1);
      add_pose(k);
      const Eigen::Isometry3d& m = d_.odometry[k];
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Odometry6Cost, 6, 4, 3, 4, 3>(new Odometry6Cost{
                                   Eigen::Quaterniond(m.linear()), m.translation(), 1.0 / c.odo_sigma_m,
                                   1.0 / c.odo_sigma_rad}),
                               nullptr, poses_[k - 1].q.coeffs().data(), poses_[k - 1].t.data(),
                               poses_[k].q.coeffs().data(), poses_[k].t.data());
    }
    std::set<int64_t> lms;
    std::set<int64_t> srcs;
    for (int k = first; k <= last; ++k) {
      for (const auto& o : d_.landmark_obs[k]) lms.insert(o.id);
      for (const auto& s : d_.sound_obs[k])
        if (tracks_[s.source].converged) srcs.insert(s.source);
    }
    for (int64_t id : lms) {
      for (const auto& ob : lm_obs_[id]) {
        if (ob.k > last) continue;
        add_pose(ob.k);
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Landmark3Cost, 3, 4, 3, 3>(
                                     new Landmark3Cost{ob.z, 1.0 / c.landmark_sigma_m, 1.0 / c.landmark_sigma_rad}),
                                 nullptr, poses_[ob.k].q.coeffs().data(), poses_[ob.k].t.data(),
                                 landmarks_[id].data());
      }
    }
    for (int64_t id : srcs) {
      SourceTrack& tr = tracks_[id];
      for (const auto& ob : tr.obs) {
        if (ob.k > last) continue;
        add_pose(ob.k);
        problem.AddResidualBlock(SoundCost(ob), nullptr, poses_[ob.k].q.coeffs().data(),
                                 poses_[ob.k].t.data(), tr.point.data());
      }
    }
    if (problem.NumResidualBlocks() == 0) return;
    std::map<int64_t, Eigen::Vector3d> before;
    for (int64_t id : srcs) before[id] = tracks_[id].point;
    const ceres::Solver::Options so = JointSolverOptions(first == 0 ? 200 : 10);
    ceres::Solver::Summary sum;
    ceres::Solve(so, &problem, &sum);
    for (int k : used_poses) poses_[k].q.normalize();
    // A source run off along an asymptote of its cone keeps its place from before the solve.
    for (int64_t id : srcs) {
      SourceTrack& tr = tracks_[id];
      double nearest = 1e300;
      for (const auto& ob : tr.obs)
        if (ob.k <= last) nearest = std::min(nearest, (tr.point - poses_[ob.k].t).norm());
      if (!(nearest <= o_.max_source_range_m)) tr.point = before[id];
    }
  }

  const LinearSimData& d_;
  const LinearMapperOptions& o_;
  std::unique_ptr<ForwardTable> forward_;
  std::vector<Pose6> poses_;
  std::map<int64_t, Eigen::Vector3d> landmarks_;
  struct LmObs {
    int k;
    Eigen::Vector3d z;
  };
  std::map<int64_t, std::vector<LmObs>> lm_obs_;
  std::map<int64_t, int> last_seen_;
  std::map<int64_t, SourceTrack> tracks_;
};

}  // namespace

LinearRunResult RunLinearArrayMapping(const LinearSimData& data, const LinearMapperOptions& options) {
  LinearMapperOptions o = options;
  if (!o.sensor_model) {
    static std::shared_ptr<const DoaSensorModel> simulated = [] {
      std::vector<double> raw, truth;
      SimulatedCalibration(7, &raw, &truth);
      return std::shared_ptr<const DoaSensorModel>(GpDoaModel::Fit(raw, truth));
    }();
    o.sensor_model = simulated;
  }
  Mapper mapper(data, o);
  return mapper.Run();
}

}  // namespace sound_map
}  // namespace sarmap
