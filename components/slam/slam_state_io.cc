// Slam's state file (Save, Load): everything needed to continue mapping or to localise after
// a restart, sealed (common/state_file.h) and written crash-safe.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "common/binary_io.h"
#include "common/state_file.h"
#include "slam/slam.h"

namespace sarmap {
namespace slam {

// Pose-graph file: little-endian binary, "SARMAPPG" + version, then the state field by field.

namespace {

class Writer : public common::BinaryWriter {
 public:
  using BinaryWriter::BinaryWriter;
  void Pose(const Rigid2d& p) {
    Pod(p.translation().x()), Pod(p.translation().y()), Pod(p.yaw_rad());
  }
  void Packed(const PackedPoints& p) {
    Pod<float>(p.step_m());
    Array(p.raw());
  }
};

class Reader : public common::BinaryReader {
 public:
  explicit Reader(std::istream* in) : BinaryReader(in, "pose-graph file") {}
  Rigid2d Pose() {
    const double x = Pod<double>(), y = Pod<double>(), t = Pod<double>();
    return Rigid2d(x, y, t);
  }
  PointCloud Cloud() { return Array<Eigen::Vector2f>(10000000); }
  PackedPoints Packed() {
    const float step_m = Pod<float>();
    try {
      return PackedPoints::FromRaw(step_m, Array<int16_t>(20000000));
    } catch (const std::invalid_argument& e) {
      Corrupt(e.what());
    }
  }
};

constexpr char kMagic[8] = {'S', 'A', 'R', 'M', 'A', 'P', 'P', 'G'};
// Of the body. Version 2 adds each constraint's translation shape, version 3 the trimmed flags
// of submaps and nodes (a trimmed submap has no grid) and each constraint's steps, version 4 the
// raster cells only trimmed submaps knew, version 5 the stored forms (a finished grid's 16-bit
// codes, a node's returns in 16-bit steps) and nothing but the poses of a node without returns,
// version 6 the counts of submaps trimming kept for their area and for new obstacles; version 1-5
// bodies are still read (shape: the identity; nothing trimmed; no such cells; grids and returns
// as floats; every live submap kept for its area).
constexpr int32_t kVersion = 6;
// The body is sealed (common/state_file.h) with this kind and version; a file of version 1 is
// an unsealed body (written before sealing).
constexpr char kStateKind[] = "slam-pose-graph";
constexpr int kStateVersion = 2;

bool Finite(const Rigid2d& p) {
  return std::isfinite(p.translation().x()) && std::isfinite(p.translation().y()) &&
         std::isfinite(p.yaw_rad());
}

}  // namespace

void Slam::Save(const std::string& path) const {
  {
    // Streamed to disk: the file (tens of MB on a long mission) is never in memory whole.
    common::SealedStateWriter file(path, kStateKind, kStateVersion);
    std::ostream& out = file.body();
    Writer w(&out);
    out.write(kMagic, 8);
    w.Pod(kVersion);
    w.Pod<double>(options_.local.resolution_m);
    // Submaps.
    w.Pod<int64_t>(submaps_.size());
    for (size_t i = 0; i < submaps_.size(); ++i) {
      const Submap& s = submaps_[i];
      w.Pose(s.local_pose);
      w.Pose(submap_global_[i]);
      w.Pod<int32_t>(s.num_inserted);
      w.Pod<int32_t>(s.finished);
      w.Pod<int32_t>(s.trimmed);
      w.Pod<int64_t>(s.pulses);
      w.Pod<int64_t>(s.samples);
      w.Pod<int64_t>(s.nodes.size());
      for (int n : s.nodes) w.Pod<int32_t>(n);
      if (s.trimmed) continue;  // no grid
      w.Pod<int32_t>(s.grid->width());
      w.Pod<int32_t>(s.grid->height());
      w.Pod<double>(s.grid->corner().x());
      w.Pod<double>(s.grid->corner().y());
      // As stored: a finished grid's 16-bit codes, a live grid's floats.
      const size_t num_cells = static_cast<size_t>(s.grid->width()) * s.grid->height();
      w.Pod<int32_t>(s.grid->finished());
      if (const uint16_t* codes = s.grid->FinishedCells()) {
        out.write(reinterpret_cast<const char*>(codes), num_cells * sizeof(uint16_t));
      } else {
        out.write(reinterpret_cast<const char*>(s.grid->LiveCells()), num_cells * sizeof(float));
      }
    }
    w.Pod<int64_t>(active_submaps_.ids().size());
    for (int a : active_submaps_.ids()) w.Pod<int32_t>(a);
    // Nodes.
    w.Pod<int64_t>(nodes_.size());
    for (size_t i = 0; i < nodes_.size(); ++i) {
      const Node& n = nodes_[i];
      w.Pod(n.time_s);
      w.Pose(n.local_pose);
      w.Pose(node_global_[i]);
      w.Pod<int32_t>(n.trimmed);
      // A trimmed node that keeps no returns (most of a long mission's) is its poses alone.
      w.Pod<int32_t>(n.data != nullptr);
      if (!n.data) continue;
      const NodeData& d = *n.data;
      w.Pod<int32_t>(d.has_odometry);
      w.Pod<int32_t>(d.odom_segment);
      w.Pose(d.odom_pose);
      w.Array(d.loop_points);
      w.Pod(d.range_data.origin.x()), w.Pod(d.range_data.origin.y());
      w.Packed(d.range_data.hits);
      w.Packed(d.range_data.misses);
    }
    // Constraints.
    w.Pod<int64_t>(constraints_.size());
    for (const Constraint& c : constraints_) {
      w.Pod<int32_t>(c.kind), w.Pod<int32_t>(c.from), w.Pod<int32_t>(c.to);
      w.Pose(c.relative);
      w.Pod(c.translation_weight), w.Pod(c.rotation_weight), w.Pod(c.score);
      w.Pod(c.translation_shape(0, 0)), w.Pod(c.translation_shape(0, 1));
      w.Pod(c.translation_shape(1, 1));
      w.Pod<int32_t>(c.steps);
    }
    // Raster cells only trimmed submaps knew, ascending (the file is the same for the same state).
    std::vector<int64_t> known(retained_known_.begin(), retained_known_.end());
    std::sort(known.begin(), known.end());
    w.Pod<int64_t>(known.size());
    for (int64_t key : known) w.Pod(key);
    // The live submaps trimming kept for their area and for new obstacles (the budget of these).
    w.Pod<int64_t>(stats_.submaps_kept_new_area);
    w.Pod<int64_t>(stats_.submaps_kept_new_obstacles);
    // Local state to continue.
    w.Pose(global_from_local_);
    w.Pod<int32_t>(extrapolator_.have_last());
    w.Pod(extrapolator_.last_time_s());
    w.Pose(extrapolator_.last_pose());
    w.Pod<int32_t>(extrapolator_.last_has_odometry());
    w.Pose(extrapolator_.last_odometry());
    w.Pod<int32_t>(extrapolator_.last_segment());
    w.Pod(motion_filter_.last_time_s());
    w.Pose(motion_filter_.last_pose());
    w.Pod<int32_t>(-1);  // unused (scans carry their own geometry); kept for the file layout
    w.Pod<int32_t>(odometry_.segment());
    out.write(kMagic, 8);  // trailer: a complete file
    file.Commit();         // throws if any write failed
  }
}

void Slam::Load(const std::string& path) {
  std::string body;
  // Throws StateFileError (another kind or version, truncated, checksum) before any parsing.
  if (common::ReadSealedState(path, kStateKind, kStateVersion, &body) ==
      common::StateFileRead::kMissing) {
    throw std::runtime_error("cannot open pose-graph file '" + path + "'");
  }
  common::MemoryStreamBuffer bytes(body.data(), body.size());  // read in place, not copied
  std::istream in(&bytes);
  Reader r(&in);
  char magic[8];
  in.read(magic, 8);
  if (!in || !std::equal(magic, magic + 8, kMagic)) {
    throw std::runtime_error("'" + path + "' is not a sarmap pose-graph file");
  }
  const int32_t body_version = r.Pod<int32_t>();
  if (body_version < 1 || body_version > kVersion) {
    throw std::runtime_error("unsupported pose-graph version");
  }
  const double resolution = r.Pod<double>();
  std::vector<Submap> submaps;
  std::vector<Rigid2d> submap_global;
  const int64_t num_submaps = r.Count(1000000);
  for (int64_t i = 0; i < num_submaps; ++i) {
    Submap s;
    s.local_pose = r.Pose();
    submap_global.push_back(r.Pose());
    s.num_inserted = r.Pod<int32_t>();
    s.finished = r.Pod<int32_t>() != 0;
    if (body_version >= 3) s.trimmed = r.Pod<int32_t>() != 0;
    s.pulses = r.Pod<int64_t>();
    s.samples = r.Pod<int64_t>();
    const int64_t nn = r.Count(100000000);
    for (int64_t k = 0; k < nn; ++k) s.nodes.push_back(r.Pod<int32_t>());
    if (s.trimmed) {
      if (i == 0 || !s.finished) {
        throw std::runtime_error("pose-graph file corrupt (trimmed submap)");
      }
      submaps.push_back(std::move(s));
      continue;
    }
    const int w = r.Pod<int32_t>(), h = r.Pod<int32_t>();
    const double cx = r.Pod<double>(), cy = r.Pod<double>();
    if (w <= 0 || h <= 0 || static_cast<int64_t>(w) * h > 400000000) {
      throw std::runtime_error("pose-graph file corrupt (grid size)");
    }
    const size_t num_cells = static_cast<size_t>(w) * h;
    s.grid = std::make_unique<ProbabilityGrid>(resolution, Eigen::Vector2d(cx, cy), 1);
    if (body_version >= 5 && r.Pod<int32_t>() != 0) {
      std::vector<uint16_t> codes(num_cells);
      in.read(reinterpret_cast<char*>(codes.data()), num_cells * sizeof(uint16_t));
      if (!in) throw std::runtime_error("pose-graph file truncated");
      if (std::any_of(codes.begin(), codes.end(), [](uint16_t v) { return v > 32767; })) {
        throw std::runtime_error("pose-graph file corrupt (grid cell)");
      }
      s.grid->SetRawFinished(w, h, Eigen::Vector2d(cx, cy), std::move(codes));
    } else {
      std::vector<float> cells(num_cells);
      in.read(reinterpret_cast<char*>(cells.data()), num_cells * sizeof(float));
      if (!in) throw std::runtime_error("pose-graph file truncated");
      s.grid->SetRaw(w, h, Eigen::Vector2d(cx, cy), std::move(cells));
    }
    if (s.finished) s.grid->Finish();
    submaps.push_back(std::move(s));
  }
  std::vector<int> active;
  const int64_t na = r.Count(2);
  for (int64_t i = 0; i < na; ++i) active.push_back(r.Pod<int32_t>());
  std::deque<Node> nodes;
  std::vector<Rigid2d> node_global;
  const int64_t num_nodes = r.Count(100000000);
  for (int64_t i = 0; i < num_nodes; ++i) {
    Node n;
    n.data = std::make_unique<NodeData>();
    NodeData& d = *n.data;
    n.time_s = r.Pod<double>();
    n.local_pose = r.Pose();
    node_global.push_back(r.Pose());
    if (body_version >= 5) {
      n.trimmed = r.Pod<int32_t>() != 0;
      if (r.Pod<int32_t>() == 0) {  // no returns: an empty NodeData, released below if trimmed
        nodes.push_back(std::move(n));
        continue;
      }
    }
    d.has_odometry = r.Pod<int32_t>() != 0;
    d.odom_segment = r.Pod<int32_t>();
    if (body_version >= 3 && body_version < 5) n.trimmed = r.Pod<int32_t>() != 0;
    d.odom_pose = r.Pose();
    d.loop_points = r.Cloud();
    d.range_data.origin.x() = r.Pod<float>();
    d.range_data.origin.y() = r.Pod<float>();
    if (body_version >= 5) {
      d.range_data.hits = r.Packed();
      d.range_data.misses = r.Packed();
    } else {
      d.range_data.hits = PackedPoints(r.Cloud());
      d.range_data.misses = PackedPoints(r.Cloud());
    }
    nodes.push_back(std::move(n));
  }
  std::vector<Constraint> constraints;
  const int64_t nc = r.Count(1000000000);
  for (int64_t i = 0; i < nc; ++i) {
    Constraint c;
    c.kind = static_cast<Constraint::Kind>(r.Pod<int32_t>());
    c.from = r.Pod<int32_t>();
    c.to = r.Pod<int32_t>();
    c.relative = r.Pose();
    c.translation_weight = r.Pod<double>();
    c.rotation_weight = r.Pod<double>();
    c.score = r.Pod<double>();
    if (body_version >= 2) {
      const double xx = r.Pod<double>(), xy = r.Pod<double>(), yy = r.Pod<double>();
      c.translation_shape << xx, xy, xy, yy;
    }
    if (body_version >= 3) c.steps = r.Pod<int32_t>();
    const bool submap_kind = c.submap_to_node();
    if (c.kind < 0 || c.kind > Constraint::TRIMMED_CHAIN || c.from < 0 || c.to < 0 ||
        c.to >= num_nodes || c.from >= (submap_kind ? num_submaps : num_nodes) || c.steps < 1) {
      throw std::runtime_error("pose-graph file corrupt (constraint)");
    }
    constraints.push_back(c);
  }
  std::unordered_set<int64_t> retained_known;
  if (body_version >= 4) {
    const int64_t nk = r.Count(1000000000);
    for (int64_t i = 0; i < nk; ++i) retained_known.insert(r.Pod<int64_t>());
  }
  // Before version 6 every live finished submap trimming judged counts as kept for its area.
  int64_t kept_new_area = -1, kept_new_obstacles = 0;
  if (body_version >= 6) {
    kept_new_area = r.Count(1000000000);
    kept_new_obstacles = r.Count(1000000000);
  }
  // Read into locals: a file refused below leaves this Slam as it was (a clean start).
  const Rigid2d global_from_local = r.Pose();
  const bool have_last_scan = r.Pod<int32_t>() != 0;
  const double last_scan_time = r.Pod<double>();
  const Rigid2d last_scan_local = r.Pose();
  const bool last_scan_has_odom = r.Pod<int32_t>() != 0;
  const Rigid2d last_scan_odom = r.Pose();
  const int32_t last_scan_segment = r.Pod<int32_t>();
  const double last_node_time = r.Pod<double>();
  const Rigid2d last_node_local = r.Pose();
  r.Pod<int32_t>();  // unused (a fixed beam count of version 2 files)
  const int32_t odom_segment = r.Pod<int32_t>();
  in.read(magic, 8);
  if (!in || !std::equal(magic, magic + 8, kMagic)) {
    throw std::runtime_error("pose-graph file '" + path + "' is incomplete");
  }
  for (int a : active) {
    if (a < 0 || a >= num_submaps || submaps[a].trimmed) {
      throw std::runtime_error("pose-graph file corrupt (active)");
    }
  }
  // Each node's submaps, from the submaps' node lists.
  int64_t submaps_trimmed = 0, nodes_trimmed = 0;
  for (size_t i = 0; i < submaps.size(); ++i) {
    submaps_trimmed += submaps[i].trimmed;
    for (int n : submaps[i].nodes) {
      if (n < 0 || n >= num_nodes) {
        throw std::runtime_error("pose-graph file corrupt (submap node)");
      }
      nodes[n].data->submaps.push_back(static_cast<int>(i));
    }
  }
  for (const Node& n : nodes) nodes_trimmed += n.trimmed;
  // A NaN pose or weight would spread through the next optimisation to the whole graph.
  bool finite = Finite(global_from_local) && Finite(last_scan_local) && Finite(last_scan_odom) &&
                Finite(last_node_local) && std::isfinite(last_scan_time) &&
                std::isfinite(last_node_time);
  for (size_t i = 0; finite && i < submaps.size(); ++i) {
    finite = Finite(submaps[i].local_pose) && Finite(submap_global[i]);
  }
  for (size_t i = 0; finite && i < nodes.size(); ++i) {
    finite = std::isfinite(nodes[i].time_s) && Finite(nodes[i].local_pose) &&
             Finite(node_global[i]) && Finite(nodes[i].data->odom_pose);
  }
  for (size_t i = 0; finite && i < constraints.size(); ++i) {
    const Constraint& c = constraints[i];
    finite = Finite(c.relative) && std::isfinite(c.translation_weight) &&
             std::isfinite(c.rotation_weight) && std::isfinite(c.score) &&
             c.translation_shape.allFinite();
  }
  if (!finite)
    throw std::runtime_error("pose-graph file '" + path + "' corrupt (non-finite value)");
  global_from_local_ = global_from_local;
  // The odometry frame of a restarted robot may differ: the first new odometry bridges the gap
  // only when it is plausible (PoseExtrapolator), and the scan matcher (wide search on the first
  // scan) finds the robot.
  extrapolator_.Restore(have_last_scan, last_scan_time, last_scan_local, last_scan_has_odom,
                        last_scan_odom, last_scan_segment, !localisation_only_);
  submaps_ = std::move(submaps);
  submap_global_ = std::move(submap_global);
  active_submaps_.Restore(std::move(active));
  for (Node& n : nodes) {
    if (n.trimmed) ReleaseTrimmedData(&n, n.data->range_data.hits.Unpack());
  }
  nodes_ = std::move(nodes);
  motion_filter_.Restore(last_node_time, last_node_local);
  chain_drift_.Clear();
  node_global_ = std::move(node_global);
  RebuildRetainedObstacles();
  retained_known_ = std::move(retained_known);
  orphan_nodes_.clear();
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) {
    const Node& n = nodes_[i];
    if (n.trimmed || !n.data || n.data->submaps.empty() || InLiveSubmap(i)) continue;
    orphan_nodes_.push_back(i);
  }
  constraints_ = std::move(constraints);
  precomputations_.clear();
  scans_.clear();
  map_drawing_.reset();  // DrawMap draws the loaded graph afresh
  drawn_nodes_.clear();
  // A new odometry segment: the odometry frame of a restarted robot may differ.
  odometry_.Reset(odom_segment + 1);
  have_scan_since_load_ = false;
  nodes_since_optimisation_ = 0;
  if (localisation_only_ && !nodes_.empty())
    extrapolator_.set_last_pose(global_from_local_ * extrapolator_.last_pose());
  stats_ = SlamStats();
  stats_.nodes = nodes_.size();
  stats_.submaps = submaps_.size();
  stats_.submaps_trimmed = submaps_trimmed;
  stats_.nodes_trimmed = nodes_trimmed;
  if (kept_new_area < 0) {
    kept_new_area = 0;
    for (size_t i = kOwnChain + 1; i < submaps_.size(); ++i) {
      kept_new_area += submaps_[i].finished && !submaps_[i].trimmed;
    }
  }
  stats_.submaps_kept_new_area = kept_new_area;
  stats_.submaps_kept_new_obstacles = kept_new_obstacles;
}

}  // namespace slam
}  // namespace sarmap
