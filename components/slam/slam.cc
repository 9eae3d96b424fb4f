#include "slam/slam.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "common/angles.h"

namespace sarmap {
namespace slam {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
// Submaps this close in sequence to the current one are treated as its local chain and not
// searched for loops (see AddNode); 0: every finished submap is searched.
constexpr int kRecentSubmaps = 0;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

namespace {
DriftModel DriftModelOf(const LoopClosureOptions& lo) {
  DriftModel m;
  m.translation_m_per_sqrt_m = lo.consistency_drift_m_per_sqrt_m;
  m.rotation_rad_per_sqrt_rad = lo.consistency_drift_deg_per_sqrt_rad * kDegToRad;
  m.rotation_rad_per_sqrt_m = lo.consistency_drift_deg_per_sqrt_m * kDegToRad;
  return m;
}
}  // namespace

Slam::Slam(const SlamOptions& options)
    : options_(options),
      odometry_(options.input, options.local),
      motion_filter_(options.local),
      extrapolator_(options.local),
      active_submaps_(options.local.scans_per_submap),
      chain_drift_(DriftModelOf(options.loop)) {}
Slam::~Slam() = default;

bool Slam::AddOdometry(double time_s, const Rigid2d& pose, std::string* why) {
  bool reordered = false;
  const bool added = odometry_.Add(time_s, pose, why, &reordered);
  stats_.reordered_odometry += reordered;
  stats_.rejected_odometry += !added;
  return added;
}

bool Slam::CheckScan(const LaserScan& scan, std::string* why) {
  const int n = static_cast<int>(scan.ranges_m.size());
  if (n < 2 || n > 100000) {
    *why = "scan has " + std::to_string(n) + " ranges";
    return false;
  }
  if (!std::isfinite(scan.angle_min_rad) || !std::isfinite(scan.angle_increment_rad) ||
      scan.angle_increment_rad == 0 || std::abs(scan.angle_increment_rad * n) > 2 * M_PI + 0.1) {
    *why = "scan angles are invalid";
    return false;
  }
  if (scan.has_base_from_laser && !(std::isfinite(scan.base_from_laser.translation().x()) &&
                                    std::isfinite(scan.base_from_laser.translation().y()) &&
                                    std::isfinite(scan.base_from_laser.yaw_rad()))) {
    *why = "scan laser pose not finite";
    return false;
  }
  if (!std::isfinite(scan.time_s)) {
    *why = "scan time not finite";
    return false;
  }
  if (!(scan.range_max_m > scan.range_min_m) || !std::isfinite(scan.range_min_m)) {
    *why = "scan range limits invalid";
    return false;
  }
  for (float r : scan.ranges_m) {
    if (std::isnan(r) || r < 0) {
      *why = std::isnan(r) ? "scan has NaN ranges" : "scan has negative ranges";
      return false;
    }
  }
  if (extrapolator_.have_last() && scan.time_s < extrapolator_.last_time_s() - 1.0) {
    *why = "scan more than 1 s older than the previous one";
    return false;
  }
  return true;
}

void Slam::ScanToRangeData(const LaserScan& scan, RangeData* data) const {
  const auto& o = options_.scan;
  const Rigid2d base_from_laser = scan.has_base_from_laser
                                      ? scan.base_from_laser
                                      : Rigid2d(o.laser_x_m, o.laser_y_m, o.laser_yaw_rad);
  data->origin = base_from_laser.translation().cast<float>();
  data->hits.clear();
  data->misses.clear();
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const float r = scan.ranges_m[i];
    const double a = scan.angle_min_rad + i * scan.angle_increment_rad + base_from_laser.yaw_rad();
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    const bool is_return =
        std::isfinite(r) && r >= scan.range_min_m && r <= scan.range_max_m && r >= o.min_range_m;
    if (is_return && r <= o.max_range_m) {
      data->hits.push_back((base_from_laser.translation() + r * dir).cast<float>());
    } else if ((!is_return && !(r < o.min_range_m) && r > scan.range_min_m) ||
               (is_return && r > o.max_range_m)) {
      if (o.missing_data_ray_length_m > 0) {
        data->misses.push_back(
            (base_from_laser.translation() + o.missing_data_ray_length_m * dir).cast<float>());
      }
    }
  }
}

Rigid2d Slam::MatchLocal(const ProbabilityGrid& grid, const PointCloud& scan_points,
                         const Rigid2d& predicted, double* score) const {
  const auto& l = options_.local;
  PointCloud known_points;
  if (l.match_known_space_only) known_points = MatchablePoints(grid, scan_points, predicted);
  // With nothing of the scan in known space (a fresh submap), every point is matched.
  const PointCloud& points = known_points.empty() ? scan_points : known_points;
  Rigid2d initial = predicted;
  if (l.use_correlative_search) {
    CorrelativeOptions c;
    c.linear_window_m = l.correlative_linear_window_m;
    c.angular_window_rad = l.correlative_angular_window_deg * kDegToRad;
    c.translation_delta_cost_weight = l.correlative_translation_cost;
    c.rotation_delta_cost_weight = l.correlative_rotation_cost;
    double csm_score = 0;
    initial = CorrelativeMatch(grid, points, predicted, c, &csm_score);
    // The prediction can be far off (wheel slip, fast turns): when the best candidate lies at
    // the edge of the window or matches poorly, search again in a wide window.
    const Rigid2d delta = predicted.inverse() * initial;
    const bool at_edge = std::abs(delta.yaw_rad()) > 0.8 * c.angular_window_rad ||
                         delta.translation().cwiseAbs().maxCoeff() > 0.8 * c.linear_window_m;
    if (at_edge || csm_score < l.wide_search_below_score) {
      c.linear_window_m = l.wide_linear_window_m;
      c.angular_window_rad = l.wide_angular_window_deg * kDegToRad;
      double wide_score = 0;
      const Rigid2d wide = CorrelativeMatch(grid, points, predicted, c, &wide_score);
      if (wide_score > csm_score) initial = wide;
    }
  }
  CeresMatcherOptions m;
  m.occupied_space_weight = l.ceres_occupied_weight;
  m.translation_weight = l.ceres_translation_weight;
  m.rotation_weight = l.ceres_rotation_weight;
  m.max_iterations = l.ceres_max_iterations;
  if (l.ceres_rotation_weight_informative > 0) {
    // Trust the odometry's heading less where the scan itself pins the heading (corners in
    // view), keep it where the scan cannot tell turning from sliding (a corridor).
    // The matcher's cost is a mean over the points; counted per point (x N), a scan of 20
    // points through glass tells less than one of 200 that sees the same walls.
    const double info =
        points.size() * RotationInformation(grid, points, initial, l.ceres_occupied_weight,
                                            l.ceres_translation_weight);
    m.rotation_weight =
        AdaptiveRotationWeight(info, l.ceres_rotation_weight, l.ceres_rotation_weight_informative,
                               l.rotation_information_low, l.rotation_information_high);
  }
  // The translation prior is the prediction (as in Cartographer): where the scan cannot tell
  // (a corridor), the prediction wins; the rotation prior is the correlative result (or the
  // prediction, for a robot whose odometry is better than what a degenerate scan tells).
  // In localisation only the map is fixed and complete: follow the correlative result, so an
  // offset of the start pose is corrected instead of held.
  const Rigid2d prior(localisation_only_ ? initial.translation() : predicted.translation(),
                      l.ceres_rotation_prior_from_prediction && !localisation_only_
                          ? predicted.yaw_rad()
                          : initial.yaw_rad());
  const Rigid2d result = CeresMatch(grid, points, prior, initial, m);
  if (score) *score = ScoreAt(grid, scan_points, result);  // comparable between predictions
  return result;
}

ScanResult Slam::AddScan(const LaserScan& scan) {
  ScanResult result;
  if (!CheckScan(scan, &result.reason)) {
    ++stats_.rejected_scans;
    return result;
  }
  // A scan stamped slightly earlier than the previous one (the Intel log does this 631 times,
  // by up to 0.9 s, in bursts whose line order is the recording order: its relations confirm
  // it) is taken in arrival order, as odometry is: it is processed at the newest input time,
  // so the prediction uses the newest odometry instead of odometry from before the previous
  // scan, and it keeps its own stamp in the trajectory.
  LaserScan reordered;
  const LaserScan* in = &scan;
  if (extrapolator_.have_last() && scan.time_s < extrapolator_.last_time_s()) {
    ++stats_.reordered_scans;
    reordered = scan;
    reordered.time_s = extrapolator_.last_time_s();
    if (!odometry_.empty() && odometry_.newest().time_s > reordered.time_s &&
        odometry_.newest().time_s - reordered.time_s < 1.0) {
      reordered.time_s = odometry_.newest().time_s;
    }
    in = &reordered;
  }
  return AddScanInOrder(*in, scan.time_s);
}

ScanResult Slam::AddScanInOrder(const LaserScan& scan, double stamp_s) {
  ScanResult result;
  if (extrapolator_.awaiting_bridge() && !localisation_only_) {
    // Restarted from saved state: the first odometry bridges the motion made while we were down
    // (PoseExtrapolator). A scan that arrives before it would be placed at the saved pose, and the
    // bridge then added on top of wherever the matcher put it (0.5-1 m off in the lab when the
    // first scans beat the odometry by 0.05-0.4 s). Such scans wait, up to kMaxResumeWaitS;
    // without odometry by then the wide search finds the robot.
    constexpr double kMaxResumeWaitS = 1.0;
    Rigid2d odom;
    int segment;
    if (!odometry_.At(scan.time_s, &odom, &segment)) {
      if (extrapolator_.KeepWaitingForBridge(scan.time_s, kMaxResumeWaitS)) {
        ++stats_.scans_waiting_for_odometry;
        result.waiting_for_odometry = true;
        result.reason = "restarted: waiting for the first odometry to bridge the gap";
        return result;
      }
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  RangeData data;
  ScanToRangeData(scan, &data);
  const auto& so = options_.scan;
  const PointCloud voxel_hits = VoxelFilter(data.hits, static_cast<float>(so.voxel_size_m));
  const PointCloud points =
      AdaptiveVoxelFilter(voxel_hits, static_cast<float>(so.adaptive_max_length_m),
                          so.adaptive_min_points, static_cast<float>(so.max_range_m));
  if (localisation_only_) {
    ScanResult r = AddScanLocalisation(scan, data, points);
    scans_.back().time_s = stamp_s;
    return r;
  }

  const ScanPrediction prediction = extrapolator_.Predict(scan.time_s, odometry_);
  if (prediction.stopped) ++stats_.stopped_scans;
  const Rigid2d& predicted = prediction.local_pose;
  Rigid2d local = predicted;
  if (!active_submaps_.empty() && submaps_[active_submaps_.matching()].num_inserted > 0 &&
      !points.empty()) {
    if (!have_scan_since_load_ && !nodes_.empty() && !extrapolator_.bridged()) {
      // First scan after loading a saved state without odometry across the gap: the robot
      // may have moved while we were down; search widely around the last pose before tracking
      // again. (With the odometry bridge the normal matching is better: a wide search can
      // slide along a corridor.)
      const int id = active_submaps_.matching();
      BranchAndBoundOptions b;
      b.linear_window_m = std::min(1.0, options_.loop.linear_window_m);
      b.angular_window_rad = options_.loop.angular_window_deg * kDegToRad;
      b.depth = options_.loop.branch_and_bound_depth;
      Rigid2d found;
      double score;
      if (BranchAndBoundMatch(*submaps_[id].grid, Precomputation(id), points, predicted, b,
                              options_.loop.min_score, &found, &score)) {
        local = found;
      }
    }
    const ProbabilityGrid& grid = *submaps_[active_submaps_.matching()].grid;
    const Rigid2d extrapolated = local;
    local = MatchLocal(grid, points, extrapolated, &result.match_score);
    if (prediction.constant_velocity && extrapolator_.have_last()) {
      // Without fresh odometry the constant-velocity extrapolation can run far ahead (a
      // mis-stamped scan in a fast turn, Intel): also track from the last pose (no motion) and
      // keep the better match.
      double still_score = 0;
      const Rigid2d still = MatchLocal(grid, points, extrapolator_.last_pose(), &still_score);
      if (still_score > result.match_score) {
        local = still;
        result.match_score = still_score;
      }
    }
  }
  stats_.local_seconds += Seconds(t0);
  ++stats_.scans;
  have_scan_since_load_ = true;
  extrapolator_.AddMatch(scan.time_s, local, prediction);

  // Motion filter.
  const auto& l = options_.local;
  const bool new_node = nodes_.empty() || motion_filter_.Moved(scan.time_s, local);
  if (new_node && !data.hits.empty()) {
    motion_filter_.NodeAdded(scan.time_s, local);
    // Insert into the active submaps (a new one every scans_per_submap insertions; the older
    // one finishes at 2 * scans_per_submap).
    if (active_submaps_.empty()) StartSubmap(local);
    RangeData local_data;
    local_data.origin = data.origin;
    local_data.hits = voxel_hits;
    local_data.misses = data.misses;
    const RangeData in_local = TransformRangeData(local_data, local);
    const std::vector<int> inserted = active_submaps_.ids();
    for (int id : inserted) {
      submaps_[id].grid->Insert(in_local, static_cast<float>(l.hit_probability),
                                static_cast<float>(l.miss_probability));
      ++submaps_[id].num_inserted;
    }
    const PointCloud loop_points =
        AdaptiveVoxelFilter(voxel_hits, static_cast<float>(so.loop_adaptive_max_length_m),
                            so.loop_adaptive_min_points, static_cast<float>(so.max_range_m));
    const int node_id = AddNode(scan.time_s, local, local_data, loop_points, inserted);
    result.is_node = true;
    const ActiveSubmaps::Change change =
        active_submaps_.AfterInsertion(submaps_[active_submaps_.ids().back()].num_inserted);
    if (change.finished >= 0) {
      FinishSubmap(change.finished);
      if (options_.trim.enabled) TrimIfCovered(change.finished);
    }
    if (change.start_new) StartSubmap(local);
    ++nodes_since_optimisation_;
    if (options_.graph.optimise_every_n_nodes > 0 &&
        nodes_since_optimisation_ >= options_.graph.optimise_every_n_nodes) {
      // Counted before the optimisation, which resets the mark.
      const bool new_closures = stats_.loop_closures > loop_closures_at_last_optimisation_;
      RunOptimisation();
      result.optimised = true;
      result.loop_closed = new_closures;
    }
    (void)node_id;
  }
  scans_.push_back(MakeScanRecord(stamp_s, local, static_cast<int>(nodes_.size()) - 1));
  result.accepted = true;
  result.node_id = static_cast<int>(nodes_.size()) - 1;
  result.map_from_base = CurrentPose();
  return result;
}

int Slam::AddNode(double time_s, const Rigid2d& local_pose, const RangeData& base_data,
                  const PointCloud& loop_points, const std::vector<int>& inserted_into) {
  const int id = static_cast<int>(nodes_.size());
  Node node;
  node.time_s = time_s;
  node.local_pose = local_pose;
  node.data = std::make_unique<NodeData>();
  node.data->has_odometry = extrapolator_.last_has_odometry();
  node.data->odom_pose = extrapolator_.last_odometry();
  node.data->odom_segment = extrapolator_.last_segment();
  node.data->loop_points = loop_points;
  node.data->range_data = PackedRangeData(base_data);
  node.data->submaps = inserted_into;
  nodes_.push_back(std::move(node));
  node_global_.push_back(global_from_local_ * local_pose);
  ++stats_.nodes;
  const auto& g = options_.graph;
  for (int s : inserted_into) {
    submaps_[s].nodes.push_back(id);
    constraints_.push_back({Constraint::INTRA_SUBMAP, s, id,
                            submaps_[s].local_pose.inverse() * local_pose,
                            g.intra_translation_weight, g.intra_rotation_weight});
  }
  if (id > 0) {
    const Node& prev = nodes_[id - 1];
    const Node& cur = nodes_[id];
    if (g.local_slam_translation_weight > 0 || g.local_slam_rotation_weight > 0) {
      constraints_.push_back({Constraint::LOCAL_SLAM, id - 1, id,
                              prev.local_pose.inverse() * cur.local_pose,
                              g.local_slam_translation_weight, g.local_slam_rotation_weight});
    }
    if (prev.data && prev.data->has_odometry && cur.data->has_odometry &&
        prev.data->odom_segment == cur.data->odom_segment &&
        (g.odometry_translation_weight > 0 || g.odometry_rotation_weight > 0)) {
      constraints_.push_back({Constraint::ODOMETRY, id - 1, id,
                              prev.data->odom_pose.inverse() * cur.data->odom_pose,
                              g.odometry_translation_weight, g.odometry_rotation_weight});
    }
  }
  // Loop closures of this node against the nearest finished submaps (each pair sampled at
  // sampling_ratio): in a building revisited again and again, every submap is near, and
  // searching them all would cost far more than it gains.
  const auto t0 = std::chrono::steady_clock::now();
  // Submaps just before the active ones share the local chain with this node: a match there
  // closes no loop, so they are skipped.
  const int recent = active_submaps_.empty() ? static_cast<int>(submaps_.size())
                                             : active_submaps_.matching() - kRecentSubmaps;
  std::vector<std::pair<double, int>> near;
  for (size_t s = 0; s < submaps_.size(); ++s) {
    if (!submaps_[s].finished || submaps_[s].trimmed || static_cast<int>(s) >= recent) continue;
    const double d = (node_global_[id].translation() - submap_global_[s].translation()).norm();
    if (d <= options_.loop.max_constraint_distance_m) near.emplace_back(d, static_cast<int>(s));
  }
  std::sort(near.begin(), near.end());
  if (static_cast<int>(near.size()) > options_.loop.max_submaps_per_node) {
    near.resize(options_.loop.max_submaps_per_node);
  }
  for (const auto& [d, s] : near) {
    if (!SampleSubmap(&submaps_[s])) continue;
    TryLoopClosure(id, s);
  }
  stats_.loop_seconds += Seconds(t0);
  return id;
}

bool Slam::SampleSubmap(Submap* s) {
  ++s->pulses;
  if (static_cast<double>(s->samples) / s->pulses < options_.loop.sampling_ratio) {
    ++s->samples;
    return true;
  }
  return false;
}

void Slam::StartSubmap(const Rigid2d& local_pose) {
  Submap s;
  s.local_pose = Rigid2d(local_pose.translation(), 0.0);
  s.grid = std::make_unique<ProbabilityGrid>(options_.local.resolution_m, local_pose.translation());
  submaps_.push_back(std::move(s));
  submap_global_.push_back(global_from_local_ * submaps_.back().local_pose);
  active_submaps_.Add(static_cast<int>(submaps_.size()) - 1);
  ++stats_.submaps;
}

void Slam::FinishSubmap(int submap_id) {
  Submap& s = submaps_[submap_id];
  s.finished = true;
  s.grid->Finish();
  // A stack cached while the submap was active (the search after a restart) holds neither
  // the later insertions nor the cropped layout.
  precomputations_.remove_if([submap_id](const auto& p) { return p.first == submap_id; });
  // Older nodes (not in this submap) against the newly finished submap.
  const auto t0 = std::chrono::steady_clock::now();
  // Nodes of this submap and of the few before it are its local chain, not loops.
  const int first_recent = std::max(0, submap_id - kRecentSubmaps);
  const int first_own = submaps_[first_recent].nodes.empty() ? static_cast<int>(nodes_.size())
                                                             : submaps_[first_recent].nodes.front();
  std::vector<int> near;
  for (int n = 0; n < first_own; ++n) {
    if (!nodes_[n].trimmed &&
        (node_global_[n].translation() - submap_global_[submap_id].translation()).norm() <=
            options_.loop.max_constraint_distance_m) {
      near.push_back(n);
    }
  }
  // At most max_old_nodes_per_submap of them, spread evenly over time.
  const int limit = options_.loop.max_old_nodes_per_submap;
  const double stride =
      near.size() > static_cast<size_t>(limit) ? double(near.size()) / limit : 1.0;
  for (double k = 0; k < near.size(); k += stride)
    TryLoopClosure(near[static_cast<size_t>(k)], submap_id);
  stats_.loop_seconds += Seconds(t0);
}

const PrecomputationStack& Slam::Precomputation(int submap_id) {
  for (auto it = precomputations_.begin(); it != precomputations_.end(); ++it) {
    if (it->first == submap_id) {
      precomputations_.splice(precomputations_.begin(), precomputations_, it);
      return *precomputations_.front().second;
    }
  }
  ++stats_.precomputations_built;
  precomputations_.emplace_front(
      submap_id, std::make_unique<PrecomputationStack>(*submaps_[submap_id].grid,
                                                       options_.loop.branch_and_bound_depth));
  while (static_cast<int>(precomputations_.size()) > options_.loop.max_cached_precomputations) {
    precomputations_.pop_back();
  }
  return *precomputations_.front().second;
}

bool Slam::TryLoopClosure(int node_id, int submap_id) {
  const Submap& s = submaps_[submap_id];
  const Node& n = nodes_[node_id];
  if (!n.data || n.data->loop_points.empty()) return false;
  const PointCloud& loop_points = n.data->loop_points;
  ++stats_.loop_searches;
  // Initial guess of the node in the submap's grid (local) frame from the global estimate.
  const Rigid2d grid_from_global = s.local_pose * submap_global_[submap_id].inverse();
  const Rigid2d initial = grid_from_global * node_global_[node_id];
  const auto& lo = options_.loop;
  BranchAndBoundOptions b;
  b.linear_window_m = lo.linear_window_m;
  b.angular_window_rad = lo.angular_window_deg * kDegToRad;
  b.depth = lo.branch_and_bound_depth;
  Rigid2d found;
  double score = 0;
  if (!BranchAndBoundMatch(*s.grid, Precomputation(submap_id), loop_points, initial, b,
                           lo.min_score, &found, &score)) {
    return false;
  }
  if (lo.reject_window_edge && OnWindowBoundary(*s.grid, loop_points, initial, b, found)) {
    ++stats_.loop_closures_at_window_edge;
    return false;
  }
  CeresMatcherOptions m;
  m.occupied_space_weight = lo.ceres_occupied_weight;
  m.translation_weight = lo.ceres_translation_weight;
  m.rotation_weight = lo.ceres_rotation_weight;
  m.max_iterations = 10;
  const Rigid2d refined = CeresMatch(*s.grid, loop_points, found, found, m);
  if (lo.consistency_gate &&
      !ConsistentWithGraph(node_id, submap_id, s.local_pose.inverse() * refined)) {
    ++stats_.loop_closures_inconsistent;
    return false;
  }
  Constraint c{
      Constraint::LOOP_CLOSURE, submap_id,         node_id, s.local_pose.inverse() * refined,
      lo.translation_weight,    lo.rotation_weight};
  c.score = score;
  if (lo.weight_by_match_information) {
    // The match's Gauss-Newton information on the translation, from the grid frame into the
    // submap frame the constraint is expressed in.
    const Eigen::Matrix2d grid_from_submap = s.local_pose.rotation().toRotationMatrix();
    const Eigen::Matrix2d information_grid =
        MapTermHessian(*s.grid, loop_points, refined, 1.0).topLeftCorner<2, 2>();
    if (!TranslationShape(grid_from_submap.transpose() * information_grid * grid_from_submap,
                          &c.translation_shape)) {
      return false;
    }
  }
  constraints_.push_back(c);
  ++stats_.loop_closures;
  return true;
}

bool Slam::ConsistentWithGraph(int node_id, int submap_id, const Rigid2d& measured) {
  const Submap& s = submaps_[submap_id];
  if (s.nodes.empty()) return true;
  while (chain_drift_.size() < num_nodes()) {
    const int id = chain_drift_.size();
    const Node& node = nodes_[static_cast<size_t>(id)];
    chain_drift_.Add(node.local_pose);
    if (node.trimmed) chain_drift_.Release(id);
  }
  // The submap's part the scan matched was drawn by its nodes near the match: the drift that
  // matters is along the path between one of them and this node. Nodes within a cell of the
  // nearest are ties; the one closest along the path is taken.
  const Eigen::Vector2d match_local = (s.local_pose * measured).translation();
  const double tie_m = options_.local.resolution_m;
  int reference = -1;
  double best_distance_m = INFINITY;
  for (int m : s.nodes) {
    const double d = (nodes_[m].local_pose.translation() - match_local).norm();
    if (d < best_distance_m - tie_m ||
        (d < best_distance_m + tie_m && std::abs(m - node_id) < std::abs(reference - node_id))) {
      best_distance_m = std::min(best_distance_m, d);
      reference = m;
    }
  }
  // The submap's axes are the local frame's (submaps are not rotated in it).
  const auto& lo = options_.loop;
  const Rigid2d predicted = submap_global_[submap_id].inverse() * node_global_[node_id];
  return LoopClosureConsistent(chain_drift_, reference, node_id, predicted, measured,
                               lo.consistency_match_sigma_m,
                               lo.consistency_match_sigma_deg * kDegToRad, lo.consistency_max_chi2);
}

void Slam::RunOptimisation(int max_iterations) {
  if (nodes_.empty()) return;
  PoseGraphOptions p;
  p.max_iterations = max_iterations > 0 ? max_iterations : options_.graph.max_iterations;
  p.huber_scale = options_.graph.huber_scale;
  const auto summary = OptimisePoseGraph(constraints_, &node_global_, &submap_global_, p);
  ++stats_.optimisations;
  stats_.optimise_seconds += summary.seconds;
  nodes_since_optimisation_ = 0;
  loop_closures_at_last_optimisation_ = stats_.loop_closures;
  const int last = static_cast<int>(nodes_.size()) - 1;
  global_from_local_ = node_global_[last] * nodes_[last].local_pose.inverse();
}

void Slam::Optimise() { RunOptimisation(options_.graph.final_max_iterations); }

Rigid2d Slam::CurrentPose() const {
  if (localisation_only_) return extrapolator_.last_pose();
  return global_from_local_ * extrapolator_.last_pose();
}

Slam::MemoryUsage Slam::Memory() const {
  MemoryUsage m;
  auto cloud = [](const PointCloud& c) { return c.capacity() * sizeof(Eigen::Vector2f); };
  for (const Submap& sm : submaps_) {
    size_t bytes =
        sizeof(Submap) + sm.nodes.capacity() * sizeof(int) +
        (sm.known_samples.capacity() + sm.occupied_samples.capacity()) * sizeof(uint32_t);
    if (sm.grid) bytes += sizeof(ProbabilityGrid) + sm.grid->MemoryBytes();
    (sm.trimmed ? m.trimmed_submaps : m.submap_grids) += bytes;
  }
  for (const auto& [id, stack] : precomputations_) m.precomputations += stack->MemoryBytes();
  for (const Node& n : nodes_) {
    size_t bytes = sizeof(Node);
    if (n.data) {
      const NodeData& d = *n.data;
      bytes += sizeof(NodeData) + cloud(d.loop_points) + d.range_data.MemoryBytes() +
               d.submaps.capacity() * sizeof(int);
    }
    (n.trimmed ? m.trimmed_nodes : m.live_nodes) += bytes;
  }
  m.graph =
      constraints_.capacity() * sizeof(Constraint) +
      (node_global_.capacity() + submap_global_.capacity()) * sizeof(Rigid2d) +
      chain_drift_.MemoryBytes() +
      (kept_nodes_.capacity() + orphan_nodes_.capacity()) * sizeof(int) +
      (retained_obstacles_.size() + retained_known_.size()) * (sizeof(int64_t) + 2 * sizeof(void*));
  m.trajectory = scans_.size() * sizeof(ScanRecord);
  return m;
}

Slam::ScanRecord Slam::MakeScanRecord(double time_s, const Rigid2d& pose, int node_id) const {
  const Rigid2d stored =
      node_id >= 0 ? nodes_[static_cast<size_t>(node_id)].local_pose.inverse() * pose : pose;
  return {time_s, static_cast<float>(stored.translation().x()),
          static_cast<float>(stored.translation().y()), static_cast<float>(stored.yaw_rad()),
          node_id};
}

std::vector<StampedPose2> Slam::Trajectory() const {
  std::vector<StampedPose2> out;
  out.reserve(scans_.size());
  for (const auto& s : scans_) {
    const Rigid2d pose = s.pose();
    const bool on_node = s.node_id >= 0 && s.node_id < static_cast<int>(nodes_.size());
    const Rigid2d g = on_node ? node_global_[s.node_id] * pose : pose;
    out.push_back({s.time_s, g.translation().x(), g.translation().y(), g.yaw_rad()});
  }
  std::stable_sort(out.begin(), out.end(), [](const StampedPose2& a, const StampedPose2& b) {
    return a.time_s < b.time_s;
  });
  return out;
}

ScanResult Slam::AddScanLocalisation(const LaserScan& scan, const RangeData&,
                                     const PointCloud& points) {
  ScanResult result;
  // Track the global pose directly; odometry predicts, the nearest finished submap corrects.
  Rigid2d odom;
  int segment;
  const bool have_odom = odometry_.At(scan.time_s, &odom, &segment);
  Rigid2d predicted = extrapolator_.last_pose();
  if (have_scan_since_load_ && have_odom && extrapolator_.last_has_odometry() &&
      segment == extrapolator_.last_segment()) {
    predicted = extrapolator_.last_pose() * (extrapolator_.last_odometry().inverse() * odom);
  }
  extrapolator_.SetLastOdometry(have_odom, odom, segment);
  int best = -1;
  double best_d = 1e300;
  for (size_t s = 0; s < submaps_.size(); ++s) {
    // The saved map is frozen: every submap with scans counts.
    if (submaps_[s].num_inserted == 0 || submaps_[s].trimmed) continue;
    const double d = (submap_global_[s].translation() - predicted.translation()).norm();
    if (d < best_d) best_d = d, best = static_cast<int>(s);
  }
  Rigid2d pose = predicted;
  if (best >= 0 && !points.empty()) {
    const Submap& s = submaps_[best];
    const Rigid2d grid_from_global = s.local_pose * submap_global_[best].inverse();
    Rigid2d in_grid = grid_from_global * predicted;
    if (!have_scan_since_load_) {
      // First scan: relocalise with a wide branch-and-bound search.
      BranchAndBoundOptions b;
      b.linear_window_m = options_.loop.linear_window_m;
      b.angular_window_rad = options_.loop.angular_window_deg * kDegToRad;
      b.depth = options_.loop.branch_and_bound_depth;
      Rigid2d found;
      double score;
      if (BranchAndBoundMatch(*s.grid, Precomputation(best), points, in_grid, b,
                              options_.loop.min_score, &found, &score)) {
        in_grid = found;
      }
    }
    in_grid = MatchLocal(*s.grid, points, in_grid, &result.match_score);
    pose = grid_from_global.inverse() * in_grid;
  }
  have_scan_since_load_ = true;
  extrapolator_.SetLast(scan.time_s, pose);
  ++stats_.scans;
  scans_.push_back(MakeScanRecord(scan.time_s, pose, -1));
  result.accepted = true;
  result.node_id = -1;
  result.map_from_base = pose;
  return result;
}

std::vector<int> Slam::HoldAnchors(const std::vector<int64_t>& requested) {
  kept_nodes_.clear();
  for (int64_t id : requested) {
    if (id >= 0 && id < num_nodes() && !nodes_[id].trimmed) {
      kept_nodes_.push_back(static_cast<int>(id));
    }
  }
  std::sort(kept_nodes_.begin(), kept_nodes_.end());
  kept_nodes_.erase(std::unique(kept_nodes_.begin(), kept_nodes_.end()), kept_nodes_.end());
  // Nodes that outlived their submaps and are no longer kept go, each keeping its returns on
  // obstacles that only trimmed submaps held (retained_obstacles_ itself: TrimNodes only
  // re-inserts keys it already holds).
  const auto released = std::stable_partition(
      orphan_nodes_.begin(), orphan_nodes_.end(),
      [&](int n) { return std::binary_search(kept_nodes_.begin(), kept_nodes_.end(), n); });
  if (released != orphan_nodes_.end()) {
    const std::vector<int> gone(released, orphan_nodes_.end());
    orphan_nodes_.erase(released, orphan_nodes_.end());
    TrimNodes(gone, retained_obstacles_);
  }
  std::vector<int> ids = {num_nodes() - 1};
  ids.insert(ids.end(), kept_nodes_.begin(), kept_nodes_.end());
  return ids;
}

namespace {
// A raster cell's integer coordinates packed into one 64-bit key (and back).
int64_t CellKey(int64_t ix, int64_t iy) {
  return static_cast<int64_t>((static_cast<uint64_t>(ix) << 32) |
                              (static_cast<uint64_t>(iy) & 0xffffffffu));
}
int64_t CellKey(const Eigen::Vector2d& p, double cell_m) {
  return CellKey(static_cast<int64_t>(std::floor(p.x() / cell_m)),
                 static_cast<int64_t>(std::floor(p.y() / cell_m)));
}
void SortUnique(std::vector<int64_t>* keys) {
  std::sort(keys->begin(), keys->end());
  keys->erase(std::unique(keys->begin(), keys->end()), keys->end());
}
}  // namespace

void Slam::SubmapCircle(int submap_id, Eigen::Vector2d* centre_m, double* radius_m) const {
  const Submap& sub = submaps_[submap_id];
  const ProbabilityGrid& g = *sub.grid;
  const Rigid2d global_from_grid = submap_global_[submap_id] * sub.local_pose.inverse();
  const Eigen::Vector2d size = Eigen::Vector2d(g.width(), g.height()) * g.resolution();
  *centre_m = global_from_grid * (g.corner() + 0.5 * size);
  *radius_m = 0.5 * size.norm();
}

void Slam::KnownCells(int submap_id, std::vector<int64_t>* known,
                      std::vector<int64_t>* occupied) {
  Submap& sub = submaps_[submap_id];
  const ProbabilityGrid& g = *sub.grid;
  const double cell_m = options_.trim.cell_m;
  const Rigid2d global_from_grid = submap_global_[submap_id] * sub.local_pose.inverse();
  if (!sub.samples_ready) {
    // Once per finished grid, in its own frame: known cells every cell_m, occupied cells every
    // cell (a thin obstacle is not missed).
    const int stride = std::max(1, static_cast<int>(std::lround(cell_m / g.resolution())));
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width(); ++x) {
        const bool sampled = y % stride == stride / 2 && x % stride == stride / 2;
        const float p = g.Raw(Eigen::Array2i(x, y));
        if (p == 0.f || (!sampled && p <= 0.5f)) continue;  // 0: unknown
        const uint32_t index = static_cast<uint32_t>(y) * g.width() + x;
        if (sampled) sub.known_samples.push_back(index);
        if (p > 0.5f) sub.occupied_samples.push_back(index);
      }
    }
    sub.known_samples.shrink_to_fit();
    sub.occupied_samples.shrink_to_fit();
    sub.samples_ready = true;
  }
  // A cell index's centre in the grid frame, then in the global frame.
  const auto centre = [&](uint32_t index) {
    const Eigen::Vector2d cell(index % g.width() + 0.5, index / g.width() + 0.5);
    return global_from_grid * (g.corner() + cell * g.resolution());
  };
  known->clear();
  occupied->clear();
  for (const uint32_t index : sub.known_samples) known->push_back(CellKey(centre(index), cell_m));
  for (const uint32_t index : sub.occupied_samples) {
    occupied->push_back(CellKey(centre(index), cell_m));
  }
  SortUnique(known);
  SortUnique(occupied);
}

// The just-finished submap s against the live submaps older than s - 2 (s - 1 holds s's first
// scans, s - 2 the scans just before: the same pass), on a raster of trim.cell_m cells in the
// map frame at their poses now. A cell of s is new when fewer than fresh_submaps of the older
// submaps know it; it is a new obstacle when s sees it occupied and none of them sees an
// obstacle within one raster cell of it (seen only on a revisit: debris come closer to, a door
// closed). s is trimmed when it maps nothing new: new cells under min_fresh_area_m2 and new
// obstacles under min_new_obstacle_m2, or new obstacles when the submaps kept for those alone
// already number obstacle_submaps_per_area_submap per submap that holds area (the live graph
// stays bounded by the explored area). What stays is the first map of each place, the one later
// scans were matched against, with what was added to it since; the freed nodes keep their
// returns on the new obstacles, so that MAP still draws them.
void Slam::TrimIfCovered(int submap_id) {
  const TrimOptions& t = options_.trim;
  if (submap_id <= kOwnChain) return;  // submap 0 holds the map frame
  if (submaps_[submap_id].trimmed) return;
  std::vector<int64_t> mine, mine_occupied;
  Eigen::Vector2d centre;
  double radius;
  SubmapCircle(submap_id, &centre, &radius);
  KnownCells(submap_id, &mine, &mine_occupied);
  std::unordered_map<int64_t, int> known_before;
  known_before.reserve(mine.size());
  for (int64_t k : mine) known_before.emplace(k, 0);
  std::unordered_set<int64_t> occupied_before;
  std::vector<int64_t> theirs, theirs_occupied;
  for (int s = 0; s < submap_id - kOwnChain; ++s) {
    if (submaps_[s].trimmed || !submaps_[s].finished) continue;
    Eigen::Vector2d other_centre;
    double other_radius;
    SubmapCircle(s, &other_centre, &other_radius);
    if ((other_centre - centre).norm() > radius + other_radius) continue;
    KnownCells(s, &theirs, &theirs_occupied);
    for (int64_t k : theirs) {
      auto it = known_before.find(k);
      if (it != known_before.end()) ++it->second;
    }
    occupied_before.insert(theirs_occupied.begin(), theirs_occupied.end());
  }
  // A cell only trimmed submaps knew counts as known by one.
  int fresh_cells = 0;
  for (auto& [key, count] : known_before) {
    count += retained_known_.count(key) > 0;
    fresh_cells += count < t.fresh_submaps;
  }
  const double cell_m2 = t.cell_m * t.cell_m;
  if (fresh_cells * cell_m2 >= t.min_fresh_area_m2) {
    ++stats_.submaps_kept_new_area;
    return;
  }
  // What trimmed nodes kept is held too (an obstacle seen again on a later revisit is not new).
  std::unordered_set<int64_t> new_obstacles;
  for (int64_t key : mine_occupied) {
    const int64_t ix = key >> 32, iy = static_cast<int32_t>(key & 0xffffffff);
    bool seen = false;
    for (int dy = -1; dy <= 1 && !seen; ++dy) {
      for (int dx = -1; dx <= 1 && !seen; ++dx) {
        const int64_t near = CellKey(ix + dx, iy + dy);
        seen = occupied_before.count(near) > 0 || retained_obstacles_.count(near) > 0;
      }
    }
    if (!seen) new_obstacles.insert(key);
  }
  if (static_cast<double>(new_obstacles.size()) * cell_m2 >= t.min_new_obstacle_m2) {
    // The area's submaps: those kept for their area and the first ones, never judged.
    const int64_t area_submaps = stats_.submaps_kept_new_area + kOwnChain + 1;
    if (stats_.submaps_kept_new_obstacles + 1 <=
        t.obstacle_submaps_per_area_submap * static_cast<double>(area_submaps)) {
      ++stats_.submaps_kept_new_obstacles;
      return;
    }
    ++stats_.submaps_trimmed_over_obstacle_budget;
  }
  for (const auto& [key, count] : known_before) {
    if (count < t.fresh_submaps) retained_known_.insert(key);
  }
  TrimSubmap(submap_id, new_obstacles);
}

// Removes submap `submap_id`, its constraints, and the nodes no live submap holds but those a
// client keeps (HoldAnchors): they stay, tied to the graph by the chains around them.
void Slam::TrimSubmap(int submap_id, const std::unordered_set<int64_t>& new_obstacles) {
  Submap& sub = submaps_[submap_id];
  sub.trimmed = true;
  sub.grid.reset();
  // Swapped out, not assigned {}: that clears a vector and keeps its capacity.
  std::vector<uint32_t>().swap(sub.known_samples);
  std::vector<uint32_t>().swap(sub.occupied_samples);
  precomputations_.remove_if([submap_id](const auto& p) { return p.first == submap_id; });
  ++stats_.submaps_trimmed;
  constraints_.erase(std::remove_if(constraints_.begin(), constraints_.end(),
                                    [&](const Constraint& c) {
                                      return c.submap_to_node() && c.from == submap_id;
                                    }),
                     constraints_.end());
  std::vector<int> freed;
  for (int n : sub.nodes) {
    if (nodes_[n].trimmed || InLiveSubmap(n)) continue;
    if (std::binary_search(kept_nodes_.begin(), kept_nodes_.end(), n)) {
      orphan_nodes_.insert(std::upper_bound(orphan_nodes_.begin(), orphan_nodes_.end(), n), n);
      continue;
    }
    freed.push_back(n);
  }
  TrimNodes(freed, new_obstacles);
}

bool Slam::InLiveSubmap(int node_id) const {
  for (int s : nodes_[node_id].data->submaps) {
    if (!submaps_[s].trimmed) return true;
  }
  return false;
}

// The chain across a run of trimmed nodes p < q, k = q - p steps: z = T_p^-1 T_q at the current
// estimate, weights w / sqrt(k) (k springs in series), so the graph stays one piece and its
// solution where it was.
void Slam::TrimNodes(const std::vector<int>& node_ids,
                     const std::unordered_set<int64_t>& new_obstacles) {
  if (node_ids.empty()) return;
  for (int n : node_ids) {
    Node& node = nodes_[n];
    node.trimmed = true;
    // Its returns on what no older submap holds stay on MAP (a low object seen from afar,
    // which later scans from close by look over).
    PointCloud kept;
    for (const Eigen::Vector2f& hit : node.data->range_data.hits.Unpack()) {
      const int64_t key = CellKey(node_global_[n] * hit.cast<double>(), options_.trim.cell_m);
      if (new_obstacles.count(key) == 0) continue;
      kept.push_back(hit);
      retained_obstacles_.insert(key);
    }
    ReleaseTrimmedData(&node, std::move(kept));
    chain_drift_.Release(n);
    ++stats_.nodes_trimmed;
  }
  auto node_gone = [&](int n) { return nodes_[n].trimmed; };
  constraints_.erase(std::remove_if(constraints_.begin(), constraints_.end(),
                                    [&](const Constraint& c) {
                                      return (!c.submap_to_node() && node_gone(c.from)) ||
                                             node_gone(c.to);
                                    }),
                     constraints_.end());
  // Bridge each run of trimmed nodes.
  const auto& g = options_.graph;
  const bool local = g.local_slam_translation_weight > 0 && g.local_slam_rotation_weight > 0;
  const double chain_wt = local ? g.local_slam_translation_weight : g.intra_translation_weight;
  const double chain_wr = local ? g.local_slam_rotation_weight : g.intra_rotation_weight;
  const int last = static_cast<int>(nodes_.size()) - 1;
  int done_up_to = -1;  // node_ids ascend: a run is bridged once
  for (int n : node_ids) {
    if (n <= done_up_to) continue;
    int p = n, q = n;
    while (p >= 0 && nodes_[p].trimmed) --p;
    while (q <= last && nodes_[q].trimmed) ++q;
    done_up_to = q;
    if (p < 0 || q > last) continue;  // nothing to tie on one side
    const int steps = q - p;
    const double series = std::sqrt(static_cast<double>(steps));
    Constraint c{Constraint::TRIMMED_CHAIN,
                 p,
                 q,
                 node_global_[p].inverse() * node_global_[q],
                 chain_wt / series,
                 chain_wr / series};
    c.steps = steps;
    constraints_.push_back(c);
  }
}

void Slam::ReleaseTrimmedData(Node* node, PointCloud kept_hits) {
  if (kept_hits.empty()) {
    node->data.reset();
    return;
  }
  auto data = std::make_unique<NodeData>();
  data->range_data.origin = node->data->range_data.origin;
  data->range_data.hits = PackedPoints(kept_hits);
  node->data = std::move(data);
}

void Slam::RebuildRetainedObstacles() {
  retained_obstacles_.clear();
  for (size_t i = 0; i < nodes_.size(); ++i) {
    if (!nodes_[i].trimmed || !nodes_[i].data) continue;
    for (const Eigen::Vector2f& hit : nodes_[i].data->range_data.hits.Unpack()) {
      retained_obstacles_.insert(
          CellKey(node_global_[i] * hit.cast<double>(), options_.trim.cell_m));
    }
  }
}

bool Slam::JointCovariance(const std::vector<int>& node_ids, Eigen::MatrixXd* covariance) const {
  PoseGraphOptions p;
  p.huber_scale = options_.graph.huber_scale;
  const CovarianceOptions& o = options_.covariance;
  const double deg = M_PI / 180;
  CovarianceModel model;
  model.intra_submap = {o.intra_sigma_m, o.intra_sigma_deg * deg};
  model.loop_closure = {o.loop_sigma_m, o.loop_sigma_deg * deg};
  model.odometry = {o.odometry_sigma_m, o.odometry_sigma_deg * deg};
  model.local_slam = {o.local_slam_sigma_m, o.local_slam_sigma_deg * deg};
  return NodeCovariance(constraints_, node_global_, submap_global_, node_ids, covariance, p, model);
}

namespace {

// The known part of `grid` as an output map (-1 unknown, 0..100).
OccupancyMap ToOccupancyMap(const ProbabilityGrid& grid) {
  OccupancyMap map;
  map.resolution_m = grid.resolution();
  Eigen::Array2i lo, hi;
  if (!grid.KnownBounds(&lo, &hi)) return map;
  map.width = hi.x() - lo.x() + 1;
  map.height = hi.y() - lo.y() + 1;
  map.origin_x_m = grid.corner().x() + lo.x() * map.resolution_m;
  map.origin_y_m = grid.corner().y() + lo.y() * map.resolution_m;
  map.cells.resize(static_cast<size_t>(map.width) * map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const float p = grid.Raw(Eigen::Array2i(x + lo.x(), y + lo.y()));
      map.cells[static_cast<size_t>(y) * map.width + x] =
          p == 0.f ? int8_t(-1) : static_cast<int8_t>(std::lround(p * 100));
    }
  }
  return map;
}

float Reach(const RangeData& base_data) {
  float reach2 = base_data.origin.squaredNorm();
  for (const Eigen::Vector2f& p : base_data.hits) reach2 = std::max(reach2, p.squaredNorm());
  for (const Eigen::Vector2f& p : base_data.misses) reach2 = std::max(reach2, p.squaredNorm());
  return std::sqrt(reach2);
}

}  // namespace

float Slam::DrawNode(int id, ProbabilityGrid* grid) const {
  const Node& node = nodes_[id];
  if (!node.data) return -1.f;
  const RangeData base_data = node.data->range_data.Unpack();
  grid->Insert(TransformRangeData(base_data, node_global_[id]),
               static_cast<float>(options_.local.hit_probability),
               static_cast<float>(options_.local.miss_probability),
               static_cast<float>(options_.scan.map_free_from_m));
  return Reach(base_data);
}

OccupancyMap Slam::RenderMap() const {
  if (nodes_.empty()) {
    OccupancyMap map;
    map.resolution_m = options_.local.resolution_m;
    return map;
  }
  ProbabilityGrid grid(options_.local.resolution_m, node_global_.front().translation());
  for (int i = 0; i < num_nodes(); ++i) DrawNode(i, &grid);
  return ToOccupancyMap(grid);
}

OccupancyMap Slam::ComposeMap() const {
  if (nodes_.empty()) return RenderMap();
  // The output lattice is RenderMap's (through the first node's position), grown to hold every
  // live submap's grid at its global pose.
  const double r = options_.local.resolution_m;
  ProbabilityGrid out(r, node_global_.front().translation());
  struct Placed {
    const ProbabilityGrid* grid;
    Rigid2d global_from_local;
    Eigen::Vector2d lo, hi;  // its map-frame bounding box
    int parity;              // of its submap id
  };
  std::vector<Placed> placed;
  for (size_t s = 0; s < submaps_.size(); ++s) {
    const Submap& submap = submaps_[s];
    if (submap.trimmed || !submap.grid) continue;
    const ProbabilityGrid& grid = *submap.grid;
    Placed p{
        &grid, submap_global_[s] * submap.local_pose.inverse(), {}, {}, static_cast<int>(s % 2)};
    const Eigen::Vector2d size = r * Eigen::Vector2d(grid.width(), grid.height());
    p.lo = p.hi = p.global_from_local * grid.corner();
    for (const Eigen::Vector2d& c :
         {Eigen::Vector2d(size.x(), 0), Eigen::Vector2d(0, size.y()), size}) {
      const Eigen::Vector2d g = p.global_from_local * Eigen::Vector2d(grid.corner() + c);
      p.lo = p.lo.cwiseMin(g);
      p.hi = p.hi.cwiseMax(g);
    }
    out.GrowToInclude(p.lo.cast<float>());
    out.GrowToInclude(p.hi.cast<float>());
    placed.push_back(p);
  }
  // Local SLAM inserts node k into submaps floor(k / n) - 1 and floor(k / n) (n =
  // scans_per_submap; the first n nodes into submap 0 alone), so the even-numbered submaps hold
  // each node once, and so do the odd-numbered ones but for the first n nodes: each parity's
  // log-odds sum is the nodes' evidence. Trimming takes submaps from either; a cell takes the
  // parity that knows it, or, when both do, the one with more evidence (larger |log-odds|).
  const int width = out.width(), height = out.height();
  const size_t num_cells = static_cast<size_t>(width) * height;
  std::vector<float> log_odds[2] = {std::vector<float>(num_cells, 0.f),
                                    std::vector<float>(num_cells, 0.f)};
  std::vector<uint8_t> known(num_cells, 0);  // bit k: parity k knows the cell
  for (const Placed& p : placed) {
    // Each output cell in the submap's box samples the submap cell under its centre:
    // q(x, y) = local_from_global * centre(x, y) = q0 + x ex + y ey.
    const Rigid2d local_from_global = p.global_from_local.inverse();
    const Eigen::Matrix2d rotation = local_from_global.rotation().toRotationMatrix();
    const Eigen::Vector2d ex = r * rotation.col(0), ey = r * rotation.col(1);
    const Eigen::Vector2d q0 = local_from_global * Eigen::Vector2d(out.corner().array() + 0.5 * r);
    const Eigen::Array2i lo = out.CellIndex(p.lo.cast<float>()).max(0);
    const Eigen::Array2i hi =
        out.CellIndex(p.hi.cast<float>()).min(Eigen::Array2i(width - 1, height - 1));
    const ProbabilityGrid& grid = *p.grid;
    std::vector<float>& sum = log_odds[p.parity];
    const uint8_t bit = static_cast<uint8_t>(1 << p.parity);
    const double inv_r = 1.0 / r;
    for (int y = lo.y(); y <= hi.y(); ++y) {
      Eigen::Vector2d q = q0 + lo.x() * ex + y * ey;
      for (int x = lo.x(); x <= hi.x(); ++x, q += ex) {
        const int cx = static_cast<int>(std::floor((q.x() - grid.corner().x()) * inv_r));
        const int cy = static_cast<int>(std::floor((q.y() - grid.corner().y()) * inv_r));
        if (cx < 0 || cy < 0 || cx >= grid.width() || cy >= grid.height()) continue;
        const float probability = grid.RawAt(static_cast<size_t>(cy) * grid.width() + cx);
        if (probability == 0.f) continue;
        const size_t i = static_cast<size_t>(y) * width + x;
        sum[i] += std::log(probability / (1.f - probability));
        known[i] |= bit;
      }
    }
  }
  std::vector<float> cells(num_cells, 0.f);
  for (size_t i = 0; i < num_cells; ++i) {
    if (!known[i]) continue;
    const float even = log_odds[0][i], odd = log_odds[1][i];
    const float l = known[i] == 1                     ? even
                    : known[i] == 2                   ? odd
                    : std::abs(even) >= std::abs(odd) ? even
                                                      : odd;
    cells[i] = std::clamp(1.f / (1.f + std::exp(-l)), kMinProbability, kMaxProbability);
  }
  out.SetRaw(width, height, out.corner(), std::move(cells));
  // Returns of obstacles only trimmed nodes hold.
  for (int i = 0; i < num_nodes(); ++i) {
    if (nodes_[i].trimmed) DrawNode(i, &out);
  }
  return ToOccupancyMap(out);
}

OccupancyMap Slam::DrawMap() {
  if (nodes_.empty()) return RenderMap();
  const auto t0 = std::chrono::steady_clock::now();
  ++map_drawing_stats_.draws;
  if (options_.scan.map_source == "submaps") {
    OccupancyMap map = ComposeMap();
    map_drawing_stats_.seconds += Seconds(t0);
    return map;
  }
  // Redraw when a drawn return has moved by more than the tolerance: a point p of a scan at
  // pose (t, R) moves by |t' - t + (R' - R) p| <= |t' - t| + |yaw' - yaw| |p|.
  const double tolerance_m = options_.scan.map_redraw_shift_cells * options_.local.resolution_m;
  bool redraw = !map_drawing_;
  for (size_t i = 0; !redraw && i < drawn_nodes_.size(); ++i) {
    const DrawnNode& d = drawn_nodes_[i];
    if (d.reach_m < 0.f) continue;  // nothing drawn
    const Rigid2d& now = node_global_[i];
    const double shift_m =
        (now.translation() - d.pose.translation()).norm() +
        std::abs(common::WrapAngle(now.yaw_rad() - d.pose.yaw_rad())) * d.reach_m;
    redraw = shift_m > tolerance_m;
  }
  size_t first = drawn_nodes_.size();
  if (redraw) {
    map_drawing_ = std::make_unique<ProbabilityGrid>(options_.local.resolution_m,
                                                     node_global_.front().translation());
    drawn_nodes_.clear();
    first = 0;
    ++map_drawing_stats_.redraws;
  }
  for (size_t i = first; i < nodes_.size(); ++i) {
    const float reach_m = DrawNode(static_cast<int>(i), map_drawing_.get());
    drawn_nodes_.push_back({node_global_[i], reach_m});
    if (nodes_[i].data) ++map_drawing_stats_.nodes_drawn;
  }
  OccupancyMap map = ToOccupancyMap(*map_drawing_);
  map_drawing_stats_.seconds += Seconds(t0);
  return map;
}

}  // namespace slam
}  // namespace sarmap
