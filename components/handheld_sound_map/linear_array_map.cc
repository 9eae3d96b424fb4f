#include "handheld_sound_map/linear_array_map.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <set>
#include <utility>

#include "handheld_sound_map/linear_array_costs.h"
#include "sound_map/joint_solver_options.h"

namespace sarmap {
namespace sound_map {

using common::Utime;
using linear_costs::Odometry6Cost;
using linear_costs::OffsetBetaCost;
using linear_costs::Pose6;
using linear_costs::WrapAngle;

namespace {

// The pose source's recent poses, interpolated (slerp) at a DOA's time; never extrapolated
// beyond max_gap (the last pose is held that long).
class PoseBuffer {
 public:
  explicit PoseBuffer(Utime max_gap) : max_gap_(max_gap) {}
  void Add(Utime t, const Eigen::Isometry3d& pose) {
    if (!poses_.empty() && t <= poses_.back().first) {
      if (t == poses_.back().first) poses_.back().second = pose;
      return;  // out of order: the node orders its inputs, so this is a clock jump back
    }
    poses_.emplace_back(t, pose);
    while (poses_.size() > 2 && poses_.front().first < t - common::SecondsToUtime(30.0))
      poses_.pop_front();
  }
  bool At(Utime t, Eigen::Isometry3d* out) const {
    if (poses_.empty()) return false;
    auto after = std::lower_bound(
        poses_.begin(), poses_.end(), t,
        [](const std::pair<Utime, Eigen::Isometry3d>& p, Utime u) { return p.first < u; });
    if (after == poses_.end()) {
      if (t - poses_.back().first > max_gap_) return false;
      *out = poses_.back().second;
      return true;
    }
    if (after->first == t || after == poses_.begin()) {
      if (after->first - t > max_gap_) return false;
      *out = after->second;
      return true;
    }
    const auto& a = *(after - 1);
    const auto& b = *after;
    if (b.first - a.first > 2 * max_gap_) return false;
    const double s = static_cast<double>(t - a.first) / static_cast<double>(b.first - a.first);
    const Eigen::Quaterniond qa(a.second.linear()), qb(b.second.linear());
    out->setIdentity();
    out->linear() = qa.slerp(s, qb).toRotationMatrix();
    out->translation() = (1 - s) * a.second.translation() + s * b.second.translation();
    return true;
  }
  bool empty() const { return poses_.empty(); }
  Utime newest() const { return poses_.back().first; }

 private:
  Utime max_gap_;
  std::deque<std::pair<Utime, Eigen::Isometry3d>> poses_;
};

double RotationAngle(const Eigen::Isometry3d& m) { return Eigen::AngleAxisd(m.linear()).angle(); }

// beta of point p from world_from_sensor `pose` and its gradient in p:
//   l = R'(p - t),  beta = atan2(l_y, r),  r = |l_xz|,
//   d beta / d l = (-l_y l_x / r, r, -l_y l_z / r) / |l|^2,  d beta / d p = (d beta / d l) R'
double BetaAndGradient(const Eigen::Isometry3d& pose, const Eigen::Vector3d& p,
                       Eigen::RowVector3d* grad) {
  const Eigen::Vector3d l = pose.inverse() * p;
  const double r = std::max(std::hypot(l.x(), l.z()), 1e-9);
  const double n2 = std::max(l.squaredNorm(), 1e-9);
  const Eigen::RowVector3d dl(-l.y() * l.x() / r / n2, r / n2, -l.y() * l.z() / r / n2);
  *grad = dl * pose.linear().transpose();
  return std::atan2(l.y(), r);
}

}  // namespace

struct LinearArraySoundMap::Impl {
  struct Keyframe {
    Utime utime = 0;
    Eigen::Isometry3d odom =
        Eigen::Isometry3d::Identity();  // odom_from_sensor as the pose source gave it
    Pose6 est;                          // map_from_sensor, optimised
  };
  struct Obs {
    int kf = 0;
    Eigen::Isometry3d kf_from_sensor =
        Eigen::Isometry3d::Identity();  // where between keyframes it was heard
    double beta = 0, var = 0;
    Utime utime = 0;
  };
  struct Track {
    int64_t id = 0;
    std::unique_ptr<MultiHypothesisSource> mh;
    bool converged = false;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    Eigen::Matrix3d point_cov = Eigen::Matrix3d::Identity();
    std::vector<Obs> obs;
    Utime first = 0, last = 0;
    bool is_person = false;
  };

  explicit Impl(const LinearArrayMapOptions& o)
      : options(o), history(common::SecondsToUtime(o.max_pose_gap_s)) {}

  LinearArrayMapOptions options;
  PoseBuffer history;
  std::vector<Keyframe> keyframes;
  std::map<int64_t, Track> tracks;         // by source id
  std::map<int64_t, int64_t> track_owner;  // DOA track id -> source id
  std::map<int64_t, int> track_misses;     // consecutive DOAs of a track outside its source's gate
  std::map<int64_t, std::vector<Obs>> pending;  // a new track's first DOAs
  std::map<int64_t, Utime> pending_utime;
  Counters* counters = nullptr;
  int64_t used = 0;
  int64_t next_id = 1;
  int keyframes_since_full = 0;

  Eigen::Isometry3d ObsPose(const Obs& o) const {
    return keyframes[o.kf].est.iso() * o.kf_from_sensor;
  }

  // Predicted beta of a converged source from `pose` and its variance through the point's
  // covariance: J P J', with J the gradient of beta in the point.
  void PredictConverged(const Track& t, const Eigen::Isometry3d& pose, double* beta,
                        double* var) const {
    Eigen::RowVector3d grad;
    *beta = BetaAndGradient(pose, t.point, &grad);
    *var = grad * t.point_cov * grad.transpose();
  }

  double Chi2(const Track& t, const Eigen::Isometry3d& pose, double beta, double var) const {
    if (t.converged) {
      double b, pv;
      PredictConverged(t, pose, &b, &pv);
      const double nu = WrapAngle(beta - b);
      return nu * nu / (var + pv);
    }
    return t.mh->chi2(pose, beta, var);
  }

  // The sum of a converged source's squared DOA residuals at p.
  double Cost(const Track& t, const Eigen::Vector3d& p) const {
    double sum = 0;
    for (const Obs& o : t.obs) {
      const double nu = WrapAngle(o.beta - LinearArrayBeta(ObsPose(o), p));
      sum += nu * nu / o.var;
    }
    return sum;
  }

  // A level array hears p and its reflection through the horizontal plane at its own height
  // at the same beta; only poses off that plane tell them apart. Keep the better one.
  // The poses that heard a source span less than level_height_spread_m in height: a source
  // and its reflection through their plane explain its DOAs equally well.
  bool HeardFromOnePlane(const Track& t) const {
    double lo = 1e300, hi = -1e300;
    for (const Obs& o : t.obs) {
      const double z = ObsPose(o).translation().z();
      lo = std::min(lo, z), hi = std::max(hi, z);
    }
    return hi - lo < options.level_height_spread_m;
  }

  Eigen::Vector3d MirrorPoint(const Track& t) const {
    double z = 0;
    for (const Obs& o : t.obs) z += ObsPose(o).translation().z();
    Eigen::Vector3d mirrored = t.point;
    if (!t.obs.empty()) mirrored.z() = 2 * z / t.obs.size() - t.point.z();
    return mirrored;
  }
  bool MirrorCheck(Track* t) const {
    if (t->obs.empty()) return false;
    const Eigen::Vector3d mirrored = MirrorPoint(*t);
    if (Cost(*t, mirrored) >= Cost(*t, t->point)) return false;
    t->point = mirrored;
    return true;
  }

  // Joint least squares (5.29) of keyframes [first, last] (first 0: everything, keyframe 0
  // held as the gauge), with the pose source's relative motion between consecutive
  // keyframes, and of the converged sources they heard; DOAs from older keyframes enter with
  // those poses held constant.
  void Optimise(int first) {
    const int last = static_cast<int>(keyframes.size()) - 1;
    if (last < 0) return;
    ceres::Problem::Options po;
    po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    ceres::EigenQuaternionManifold quat;
    std::set<int> used_poses;
    auto add_pose = [&](int k) {
      if (!used_poses.insert(k).second) return;
      problem.AddParameterBlock(keyframes[k].est.q.coeffs().data(), 4, &quat);
      problem.AddParameterBlock(keyframes[k].est.t.data(), 3);
      if (k < first || k == 0) {
        problem.SetParameterBlockConstant(keyframes[k].est.q.coeffs().data());
        problem.SetParameterBlockConstant(keyframes[k].est.t.data());
      }
    };
    const LinearArrayMapOptions& o = options;
    for (int k = std::max(1, first); k <= last; ++k) {
      add_pose(k - 1);
      add_pose(k);
      const Eigen::Isometry3d rel = keyframes[k - 1].odom.inverse() * keyframes[k].odom;
      const double dist = rel.translation().norm();
      const double st = o.odometry_sigma_floor_m + o.odometry_sigma_m_per_m * dist;
      const double sr =
          (o.odometry_sigma_floor_deg + o.odometry_sigma_deg_per_m * dist) * M_PI / 180;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<Odometry6Cost, 6, 4, 3, 4, 3>(new Odometry6Cost{
              Eigen::Quaterniond(rel.linear()), rel.translation(), 1.0 / st, 1.0 / sr}),
          nullptr, keyframes[k - 1].est.q.coeffs().data(), keyframes[k - 1].est.t.data(),
          keyframes[k].est.q.coeffs().data(), keyframes[k].est.t.data());
    }
    std::vector<Track*> sources;
    for (auto& kv : tracks) {
      Track& t = kv.second;
      if (!t.converged) continue;
      const bool in_window =
          std::any_of(t.obs.begin(), t.obs.end(), [&](const Obs& ob) { return ob.kf >= first; });
      if (!in_window) continue;
      sources.push_back(&t);
      for (const Obs& ob : t.obs) {
        add_pose(ob.kf);
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<OffsetBetaCost, 1, 4, 3, 3>(
                new OffsetBetaCost{ob.kf_from_sensor.linear(), ob.kf_from_sensor.translation(),
                                   ob.beta, 1.0 / std::sqrt(ob.var)}),
            nullptr, keyframes[ob.kf].est.q.coeffs().data(), keyframes[ob.kf].est.t.data(),
            t.point.data());
      }
    }
    if (problem.NumResidualBlocks() == 0) return;
    std::vector<Eigen::Vector3d> before;
    for (Track* t : sources) before.push_back(t->point);
    const ceres::Solver::Options so = JointSolverOptions(first == 0 ? 100 : 10);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    for (int k : used_poses) keyframes[k].est.q.normalize();
    // A source run off along an asymptote of its cone (far away its angles barely change)
    // keeps its place from before the solve.
    for (size_t i = 0; i < sources.size(); ++i) {
      double nearest = 1e300;
      for (const Obs& ob : sources[i]->obs) nearest = std::min(nearest, (sources[i]->point - ObsPose(ob).translation()).norm());
      if (!(nearest <= options.max_source_range_m)) {
        sources[i]->point = before[i];
        ++counters->runaway_solves;
      }
    }
    for (Track* t : sources) {
      if (options.mirror_check && MirrorCheck(t)) ++counters->mirrors_flipped;
      UpdatePointCovariance(t);
    }
  }

  // The point's covariance from its DOAs with the poses held: (J'J)^-1 of the whitened beta
  // residuals. A level array at the source's height leaves the height unobservable; a weak
  // prior (10 m) keeps the inverse finite.
  void UpdatePointCovariance(Track* t) const {
    Eigen::Matrix3d info = Eigen::Matrix3d::Identity() * 1e-2;
    for (const Obs& ob : t->obs) {
      Eigen::RowVector3d grad;
      BetaAndGradient(ObsPose(ob), t->point, &grad);
      info += grad.transpose() * grad / ob.var;
    }
    t->point_cov = info.inverse();
  }

  // The best source for one DOA under `gate` (converged sources; initialising ones with
  // min_obs DOAs too), or -1.
  int64_t BestUnder(const Obs& ob, double gate, int min_obs) const {
    int64_t sid = -1;
    double best = gate;
    const Eigen::Isometry3d pose = ObsPose(ob);
    for (const auto& kv : tracks) {
      const Track& t = kv.second;
      if (!t.converged && static_cast<int>(t.obs.size()) < min_obs) continue;
      const double c2 = Chi2(t, pose, ob.beta, ob.var);
      if (c2 < best) best = c2, sid = kv.first;
    }
    return sid;
  }

  // The converged source within `gate` of every one of a new track's DOAs (the smallest sum),
  // or -1. Only a converged source has a place definite enough: a cone that is still
  // initialising would take any DOA near its wide hypotheses.
  // A source heard in the same block as one of the track's DOAs was another track: one
  // emitter gives one DOA per block.
  int64_t BestForAll(const std::vector<Obs>& obs, double gate) const {
    int64_t sid = -1;
    double best = 1e300;
    for (const auto& kv : tracks) {
      const Track& t = kv.second;
      if (!t.converged) continue;
      Track probe;
      probe.obs = obs;
      if (Simultaneous(probe, t)) continue;
      double sum = 0;
      bool all = true;
      for (const Obs& ob : obs) {
        const double c2 = Chi2(t, ObsPose(ob), ob.beta, ob.var);
        all = all && c2 < gate;
        sum += c2;
      }
      if (all && sum < best) best = sum, sid = kv.first;
    }
    return sid;
  }

  // Whether `obs` were heard from places far enough apart to tell a converged source from
  // another emitter on its cone from the first of them: the parallax, the largest angle the
  // array positions subtend at the source, must reach the gate in DOA standard deviations
  // (sqrt(gate_chi2) sigma), the largest change of beta such a second emitter could hide in.
  bool Discriminates(const Track& t, const std::vector<Obs>& obs) const {
    if (obs.empty()) return false;
    const Eigen::Vector3d first = ObsPose(obs.front()).translation() - t.point;
    double parallax = 0, var = 0;
    for (const Obs& ob : obs) {
      const Eigen::Vector3d here = ObsPose(ob).translation() - t.point;
      parallax = std::max(parallax, std::atan2(first.cross(here).norm(), first.dot(here)));
      var += ob.var;
    }
    return parallax >= std::sqrt(options.gate_chi2 * var / obs.size());
  }

  // One DOA to source `sid` (-1: a new source seeded by it). Returns the source's id (it
  // changes when the source converges onto a duplicate and merges into it).
  int64_t Feed(int64_t sid, const Obs& ob, Utime utime, std::set<int64_t>* taken) {
    if (sid >= 0 && taken->count(sid)) {
      ++counters->doas_duplicate;
      return sid;
    }
    const Eigen::Isometry3d pose = ObsPose(ob);
    if (sid < 0) {
      Track t;
      t.id = next_id++;
      t.mh = std::make_unique<MultiHypothesisSource>(options.hypotheses, pose, ob.beta, ob.var);
      t.first = t.last = utime;
      t.obs.push_back(ob);
      sid = t.id;
      tracks.emplace(sid, std::move(t));
      ++counters->sources_born;
    } else {
      Track& t = tracks.at(sid);
      t.obs.push_back(ob);
      t.last = utime;
      if (!t.converged) {
        t.mh->Update(pose, ob.beta, ob.var);
        if (t.mh->Failed()) {  // the cone was seeded from a bad DOA: start again from this one
          t.mh = std::make_unique<MultiHypothesisSource>(options.hypotheses, pose, ob.beta, ob.var);
          ++counters->sources_restarted;
        } else if (t.mh->converged()) {
          Converge(&t);
          sid = MergeDuplicate(&t);  // `t` may be gone after this
        }
      }
    }
    taken->insert(sid);
    ++used;
    return sid;
  }

  // A converged source on the wrong side of its array plane fits the DOAs heard from the
  // other side of it only as its mirror image: flip it when that explains all its DOAs and
  // this one better.
  bool FlipToFit(Track* t, const Obs& ob) {
    Track trial;
    trial.converged = true;
    trial.point = MirrorPoint(*t);
    trial.point_cov = t->point_cov;
    if (Chi2(trial, ObsPose(ob), ob.beta, ob.var) >= options.update_gate_chi2) return false;
    t->obs.push_back(ob);
    const bool better = Cost(*t, trial.point) < Cost(*t, t->point);
    t->obs.pop_back();
    if (!better) return false;
    t->point = trial.point;
    UpdatePointCovariance(t);
    ++counters->mirrors_flipped;
    return true;
  }

  void Converge(Track* t) {
    t->converged = true;
    t->point = t->mh->MeanPoint();
    if (!t->mh->Clustered()) {
      // Converged as a mirror pair (a level array that never left its plane): the survivors'
      // mean once reflected to the upper side; which side is true is unknown (see
      // UpdatePointCovariance). Not the plane itself: a source off the plane put on it would
      // drag its horizontal position to keep its distance.
      const double plane = t->mh->axis().origin.z();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int n = 0;
      for (const auto& h : t->mh->hypotheses()) {
        if (!h.alive) continue;
        Eigen::Vector3d p = HypothesisPoint(t->mh->axis(), h.s);
        p.z() = plane + std::abs(p.z() - plane);
        sum += p;
        ++n;
      }
      if (n) t->point = sum / n;
    }
    ++counters->sources_converged;
    if (options.mirror_check && MirrorCheck(t)) ++counters->mirrors_flipped;
    UpdatePointCovariance(t);
  }

  // Two sources heard in one block are two emitters (one DOA per emitter and block).
  static bool Simultaneous(const Track& a, const Track& b) {
    std::set<Utime> times;
    for (const Obs& o : a.obs) times.insert(o.utime);
    return std::any_of(b.obs.begin(), b.obs.end(),
                       [&](const Obs& o) { return times.count(o.utime) > 0; });
  }

  // A source heard under several track ids initialises once per track and converges more
  // than once at one place. Two converged sources closer than merge_radius_m become the older
  // one with the DOAs of both; its point is re-solved by the next optimisation. (Not by
  // chi-square: a source just converged near endfire has metres of covariance, and would
  // swallow its neighbours.) Returns the surviving id.
  int64_t MergeDuplicate(Track* t) {
    for (auto& kv : tracks) {
      Track& other = kv.second;
      if (&other == t || !other.converged) continue;
      if ((t->point - other.point).norm() > options.merge_radius_m || Simultaneous(*t, other))
        continue;
      Track* keep = other.id < t->id ? &other : t;
      Track* drop = keep == t ? &other : t;
      keep->obs.insert(keep->obs.end(), drop->obs.begin(), drop->obs.end());
      keep->first = std::min(keep->first, drop->first);
      keep->last = std::max(keep->last, drop->last);
      keep->is_person = keep->is_person || drop->is_person;
      const int64_t dropped = drop->id;
      for (auto& ow : track_owner)
        if (ow.second == dropped) ow.second = keep->id;
      UpdatePointCovariance(keep);
      const int64_t kept = keep->id;
      tracks.erase(dropped);
      ++counters->sources_merged;
      return kept;
    }
    return t->id;
  }
};

LinearArraySoundMap::LinearArraySoundMap(const LinearArrayMapOptions& options)
    : impl_(std::make_unique<Impl>(options)) {
  impl_->counters = &counters_;
}
LinearArraySoundMap::~LinearArraySoundMap() = default;

size_t LinearArraySoundMap::num_keyframes() const { return impl_->keyframes.size(); }

void LinearArraySoundMap::OnPose(Utime utime, const Eigen::Isometry3d& odom_from_sensor) {
  if (!odom_from_sensor.matrix().allFinite()) return;
  impl_->history.Add(utime, odom_from_sensor);
  ++counters_.poses;
}

void LinearArraySoundMap::OnDoa(Utime utime, const std::vector<Doa>& doas) {
  Impl& m = *impl_;
  const LinearArrayMapOptions& o = m.options;
  counters_.doas += doas.size();
  if (doas.empty()) return;
  Eigen::Isometry3d odom;
  if (!m.history.At(utime, &odom)) {
    counters_.doas_without_pose += doas.size();
    return;
  }

  // A keyframe when the rig moved far enough since the last one (5.28: the optimisation's poses).
  bool new_keyframe = m.keyframes.empty();
  if (!new_keyframe) {
    const Eigen::Isometry3d rel = m.keyframes.back().odom.inverse() * odom;
    new_keyframe = rel.translation().norm() >= o.keyframe_distance_m ||
                   RotationAngle(rel) >= o.keyframe_angle_deg * M_PI / 180;
  }
  if (new_keyframe) {
    Impl::Keyframe kf;
    kf.utime = utime;
    kf.odom = odom;
    kf.est = m.keyframes.empty() ? Pose6::From(odom)
                                 : Pose6::From(m.keyframes.back().est.iso() *
                                               (m.keyframes.back().odom.inverse() * odom));
    m.keyframes.push_back(kf);
    ++counters_.keyframes;
    ++m.keyframes_since_full;
    const int n = static_cast<int>(m.keyframes.size());
    if (o.full_optimisation_keyframes > 0 &&
        m.keyframes_since_full >= o.full_optimisation_keyframes) {
      m.Optimise(0);
      m.keyframes_since_full = 0;
      ++counters_.full_optimisations;
    } else if (n > 1) {
      m.Optimise(std::max(1, n - o.window_keyframes));
      ++counters_.window_optimisations;
    }
  }
  const int kf = static_cast<int>(m.keyframes.size()) - 1;
  const Eigen::Isometry3d kf_from_sensor = m.keyframes[kf].odom.inverse() * odom;

  std::set<int64_t> taken;  // one DOA per source per block
  for (const Doa& d : doas) {
    if (!std::isfinite(d.beta_rad) || !std::isfinite(d.sigma_rad) ||
        std::abs(d.beta_rad) > M_PI / 2 + 1e-9) {
      ++counters_.doas_invalid;
      continue;
    }
    const double sigma = std::max(d.sigma_rad, o.doa_sigma_floor_deg * M_PI / 180);
    const Impl::Obs ob{kf, kf_from_sensor, d.beta_rad, sigma * sigma, utime};
    if (d.track_id < 0) {
      // Untracked: the best source under the gate, else a new one.
      m.Feed(m.BestUnder(ob, o.gate_chi2, o.associate_min_observations), ob, utime, &taken);
      continue;
    }
    auto own = m.track_owner.find(d.track_id);
    if (own != m.track_owner.end() && !m.tracks.count(own->second)) {
      m.track_owner.erase(own);
      own = m.track_owner.end();
    }
    if (own != m.track_owner.end()) {
      // A bound track: an initialising source takes all its DOAs (its cone's own tests judge
      // them); a converged one those within its gate, or its mirror image's (then it flips).
      Impl::Track& t = m.tracks.at(own->second);
      int& misses = m.track_misses[d.track_id];
      const bool fits =
          !taken.count(t.id) &&
          (!t.converged || m.Chi2(t, m.ObsPose(ob), ob.beta, ob.var) < o.update_gate_chi2 ||
           m.FlipToFit(&t, ob));
      if (fits) {
        misses = 0;
        m.Feed(t.id, ob, utime, &taken);
        continue;
      }
      // (A source that already took another track's DOA in this block is a miss too.)
      // Outside the gate: an outlier of the source (a reflection, a DOA pulled by another
      // emitter), unless the track keeps missing: then the tracker's id moved to another
      // emitter, and the track is released and starts over.
      ++counters_.doas_gated_out;
      if (++misses < o.track_release_misses) continue;
      m.track_owner.erase(own);
      m.track_misses.erase(d.track_id);
    }
    // A new track. Its first confirm_observations DOAs, from different poses, decide whether
    // it is a converged source heard again (every one within that source's gate) or a new one.
    auto& pending = m.pending[d.track_id];
    pending.push_back(ob);
    m.pending_utime[d.track_id] = utime;
    if (static_cast<int>(pending.size()) < o.confirm_observations) continue;
    int64_t sid = m.BestForAll(pending, o.gate_chi2);
    // Heard from nearly one place, DOAs that fit a known source fit any place on its cone as
    // well: the track waits for more DOAs until they could have told the source from another
    // emitter on that cone.
    if (sid >= 0 && !m.Discriminates(m.tracks.at(sid), pending)) continue;
    for (const Impl::Obs& p : pending) {
      // One DOA per source per block: the earlier DOAs of the track belong to earlier blocks.
      std::set<int64_t> earlier_block;
      sid = m.Feed(sid, p, p.utime, p.utime == utime ? &taken : &earlier_block);
    }
    m.track_owner[d.track_id] = sid;
    m.pending.erase(d.track_id);
    m.pending_utime.erase(d.track_id);
  }
  counters_.doas_used = m.used;
  // Tracks that never reached confirm_observations DOAs are forgotten after prune_after_s.
  for (auto it = m.pending_utime.begin(); it != m.pending_utime.end();) {
    if (utime - it->second > common::SecondsToUtime(o.prune_after_s)) {
      m.pending.erase(it->first);
      it = m.pending_utime.erase(it);
    } else {
      ++it;
    }
  }

  // Sources that never converged and fell silent early are dropped (reflections, bursts).
  for (auto it = m.tracks.begin(); it != m.tracks.end();) {
    const Impl::Track& t = it->second;
    if (!t.converged && utime - t.last > common::SecondsToUtime(o.prune_after_s) &&
        static_cast<int>(t.obs.size()) < o.prune_min_observations) {
      for (auto ow = m.track_owner.begin(); ow != m.track_owner.end();)
        ow = ow->second == it->first ? m.track_owner.erase(ow) : std::next(ow);
      it = m.tracks.erase(it);
      ++counters_.sources_pruned;
    } else {
      ++it;
    }
  }
}

bool LinearArraySoundMap::OnHeardDirection(Utime utime, const Doa& doa) {
  Impl& m = *impl_;
  Eigen::Isometry3d odom;
  if (m.keyframes.empty() || !std::isfinite(doa.beta_rad) || !m.history.At(utime, &odom))
    return false;
  const Eigen::Isometry3d pose =
      m.keyframes.back().est.iso() * (m.keyframes.back().odom.inverse() * odom);
  const double sigma = std::max(doa.sigma_rad, m.options.doa_sigma_floor_deg * M_PI / 180);
  Impl::Track* best = nullptr;
  double best_chi2 = m.options.gate_chi2;
  for (auto& kv : m.tracks) {
    const double c2 = m.Chi2(kv.second, pose, doa.beta_rad, sigma * sigma);
    if (c2 < best_chi2) best_chi2 = c2, best = &kv.second;
  }
  if (!best) return false;
  best->is_person = true;
  return true;
}

void LinearArraySoundMap::Finish() {
  if (impl_->keyframes.size() < 2) return;
  impl_->Optimise(0);
  ++counters_.full_optimisations;
  if (impl_->options.mirror_check) {
    bool flipped = false;
    for (auto& kv : impl_->tracks)
      if (kv.second.converged && impl_->MirrorCheck(&kv.second)) {
        flipped = true;
        ++counters_.mirrors_flipped;
        impl_->UpdatePointCovariance(&kv.second);
      }
    if (flipped) impl_->Optimise(0);
  }
  impl_->keyframes_since_full = 0;
}

std::vector<LinearArraySoundMap::Source> LinearArraySoundMap::sources() const {
  std::vector<Source> out;
  for (const auto& kv : impl_->tracks) {
    const Impl::Track& t = kv.second;
    Source s;
    s.id = t.id;
    s.converged = t.converged;
    s.observations = static_cast<int>(t.obs.size());
    s.first_heard = t.first;
    s.last_heard = t.last;
    s.is_person = t.is_person;
    for (const auto& ow : impl_->track_owner)
      if (ow.second == t.id) s.track_ids.push_back(ow.first);
    if (t.converged) {
      s.position_m = t.point;
      s.covariance = t.point_cov;
      // Heard from one height only, the source and its mirror image fit alike: the height is
      // one of two, z or its reflection, and the reported variance says so.
      if (impl_->HeardFromOnePlane(t)) {
        const double half = 0.5 * (t.point.z() - impl_->MirrorPoint(t).z());
        s.covariance(2, 2) += half * half;
      }
      s.hypotheses_left = 1;
    } else {
      // Initialising: the survivors' mean and their spread (plus a metre: not yet a position).
      s.position_m = t.mh->MeanPoint();
      Eigen::Matrix3d spread = Eigen::Matrix3d::Identity();
      int n = 0;
      for (const auto& h : t.mh->hypotheses()) {
        if (!h.alive) continue;
        const Eigen::Vector3d d = HypothesisPoint(t.mh->axis(), h.s) - s.position_m;
        spread += d * d.transpose();
        ++n;
      }
      s.covariance = n > 1 ? Eigen::Matrix3d(spread / n) : spread;
      s.hypotheses_left = t.mh->alive();
    }
    out.push_back(s);
  }
  return out;
}

bool LinearArraySoundMap::CurrentPose(Eigen::Isometry3d* map_from_sensor) const {
  Eigen::Isometry3d odom;
  if (impl_->keyframes.empty() || impl_->history.empty() ||
      !impl_->history.At(impl_->history.newest(), &odom))
    return false;
  const auto& kf = impl_->keyframes.back();
  *map_from_sensor = kf.est.iso() * (kf.odom.inverse() * odom);
  return true;
}

Eigen::Isometry3d LinearArraySoundMap::MapFromOdom() const {
  if (impl_->keyframes.empty()) return Eigen::Isometry3d::Identity();
  const auto& kf = impl_->keyframes.back();
  return kf.est.iso() * kf.odom.inverse();
}

}  // namespace sound_map
}  // namespace sarmap
