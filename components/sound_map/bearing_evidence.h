#pragma once
// Sound sources found where many bearings cross (no LCM): every DOA is kept as a ray on the
// floor, and sources are the points the rays agree on.
//
// The IDP EKF (online_sound_map.h) starts a source from a run of agreeing DOAs and takes DOAs
// only while the robot turns slowly. A person calling every few seconds from behind furniture
// gives it a few bearings at a time, each run from one place, and is never placed. This map
// keeps every bearing (also those heard while turning, with a wider spread) and solves for all
// sources at once:
//
//   Each ray r (origin o_r, map bearing theta_r, std sigma_r) comes from a source in one cell c
//   or from clutter (reflections, the robot's own noise, a moving talker):
//     p(r) = sum_c pi_c a_rc + pi_0 a_0,   a_0 = 1 / (2 pi) (a bearing anywhere),
//     a_rc = N(theta_r - bearing(o_r -> c); 0, sigma_r^2) for cells min_range_m-max_range_m away.
//   EM on the mixture weights (as ML-EM in emission tomography), from uniform weights:
//     pi_c <- (1/N) sum_r pi_c a_rc / p(r).
//   Mass gathers where rays from different places cross; a cell crossed only by rays from one
//   place keeps no more than its share of a line. EM stops after `iterations` steps: run to
//   convergence it would put a spike wherever two rays cross.
//
// Sources: the greatest mass within peak_radius_m of a cell, greedily, 2 peak_radius_m apart,
// each with at least min_rays rays more than half explained by it. A source's position is the
// centroid of that mass. Its covariance is the inverse of the triangulation's information
//     I = sum_r w_r n_r n_r^T / (sigma_r d_r)^2
// (w_r the ray's responsibility for the source, d_r its range, n_r its unit normal), so a source
// seen from one direction only has an unbounded range, plus the spread of the mass (the rays
// share pose errors and biases, which the information takes as independent). Rays are stored
// in the frame of the SLAM node they were heard from and placed with the node's latest pose at
// every solve, so loop closures move them.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/binary_io.h"
#include "common/options.h"
#include "sound_map/sound_geometry.h"

namespace sarmap {
namespace sound_map {

struct BearingEvidenceOptions {
  bool enabled = true;
  double cell_m = 0.2;           // grid resolution (positions are centroids: finer than this)
  double min_range_m = 0.3;      // the robot itself
  double max_range_m = 8.0;      // a ray counts up to this range
  double sigma_floor_deg = 3.0;  // lower bound on a DOA's std
  double window_sigmas = 3.0;    // a ray covers cells within this many stds of its bearing
  // While the robot turns, a DOA (a window of a few hundred ms, smoothed by the localiser's
  // tracker) is heard with the heading of about turn_lag_s earlier: the sound map turns it back
  // by the yaw rate times turn_lag_s and widens it by half that (OnlineSoundMap::AddRay).
  double turn_lag_s = 0.3;
  int iterations = 30;          // EM iterations per solve
  double peak_radius_m = 0.5;   // mass summed within this radius; sources 2x this apart
  double min_rays = 30;         // rays more than half explained by a source
  double solve_period_s = 5.0;  // message time between solves
  // Beyond this many rays, rays heard from the same place in the same direction are merged
  // into one that stands for all; if that is not enough the oldest go (memory and solve time
  // stay bounded; a source heard long ago keeps its evidence).
  int max_rays = 10000;
  // A source this close to a placed source of the IDP EKF is that emitter, published once: by
  // the EKF when it is placed at least as well, else by this map.
  double merge_radius_m = 1.0;
  template <class V>
  void Visit(V& v) {
    v("enabled", enabled, "also find sources where the bearings cross (all DOAs, a batch solve)");
    v("cell_m", cell_m, "grid cell, m", Positive());
    v("min_range_m", min_range_m, "a ray starts this far from the array, m", NonNegative());
    v("max_range_m", max_range_m, "a ray counts up to this range, m");
    v("sigma_floor_deg", sigma_floor_deg, "lower bound on a DOA's std, deg", Positive());
    v("window_sigmas", window_sigmas, "a ray covers cells within this many stds of its bearing",
      Positive());
    v("turn_lag_s", turn_lag_s,
      "a DOA's lag behind the heading while turning, s: it is turned back by the yaw rate times "
      "this, and its std grows by half that",
      NonNegative());
    v("iterations", iterations, "EM iterations per solve", AtLeast(1));
    v("peak_radius_m", peak_radius_m,
      "a source's mass is summed within this radius; sources lie twice this apart", Positive());
    v("min_rays", min_rays, "a source explains more than half of each of at least this many rays",
      Positive());
    v("solve_period_s", solve_period_s, "message time between solves, s", Positive());
    v("max_rays", max_rays,
      "rays kept; beyond this, rays within 0.5 m of one another, in bearing bins of half "
      "sigma_floor_deg and of one class, merge into one that stands for all; then the oldest go",
      AtLeast(100));
    v("merge_radius_m", merge_radius_m,
      "a source this close to a placed EKF source is that emitter (published once, by the better "
      "placed), m",
      NonNegative());
  }
  void Validate(common::Validator& check) const {
    check.That(max_range_m > min_range_m, "max_range_m", "must exceed min_range_m");
  }
};

class BearingEvidence {
 public:
  // One bearing heard from the array at base pose node_pose ∘ node_from_base (node -1: the map
  // frame itself, node_from_base = map_from_base).
  struct Ray {
    int64_t utime = 0;
    int64_t node = -1;
    Pose2 node_from_base;
    double azimuth_rad = 0;  // array frame, planar
    double sigma_rad = 0;
    int sound_class = 0;  // OnlineSoundMap::SoundClass
    bool heard = false;   // a heard person's direction (PEOPLE_AUDIO), not a DOA
    bool called = false;  // ... and a keyword came with it
    double weight = 1;    // rays it stands for (rays are merged beyond max_rays)
  };
  struct Source {
    Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
    double rays = 0;          // rays' worth of mass
    double strong_rays = 0;   // rays' worth at least half explained by this source
    double parallax_rad = 0;  // angle between the farthest-apart directions it was heard from
    std::array<double, 5> class_votes{};
    bool heard = false, called = false;
    int64_t first_utime = 0, last_utime = 0;
    Eigen::Vector2d nearest_origin_m =
        Eigen::Vector2d::Zero();  // array origin of the ray that saw it closest
    double largest_sigma_m = 0;
  };

  BearingEvidence(const BearingEvidenceOptions& options, const ArrayMount& mount)
      : options_(options), mount_(mount) {}

  void Add(const Ray& ray);
  // Solves with the nodes' latest poses; with a box (the site), only the sources inside it.
  // Heard rays mark the sources they point at (within their window) as heard.
  // Each ray's cells are kept while its node moves it less than a quarter cell.
  std::vector<Source> Solve(const std::map<int64_t, Pose2>& node_poses,
                            const Eigen::Vector2d* min_m, const Eigen::Vector2d* max_m);
  size_t size() const { return rays_.size() + heard_.size(); }

  void Save(common::BinaryWriter* w) const;
  void Load(common::BinaryReader* r);  // throws on a malformed state

 private:
  // A ray placed in the map: array origin and map-frame bearing, with its std.
  struct Placed {
    Eigen::Vector2d origin{NAN, NAN};
    double bearing = 0, sigma = 0;
  };
  // A cell (floor(x / cell_m), floor(y / cell_m)) a ray covers and the bearing likelihood of a
  // source at its centre.
  struct Cell {
    int32_t ix, iy;
    float a;
  };
  struct Cache {
    Placed placed;
    std::vector<Cell> cells;
  };
  static int64_t Key(int32_t ix, int32_t iy) {
    return (static_cast<int64_t>(ix) << 32) | static_cast<uint32_t>(iy);
  }
  static int32_t KeyX(int64_t key) { return static_cast<int32_t>(key >> 32); }
  static int32_t KeyY(int64_t key) { return static_cast<int32_t>(key & 0xffffffff); }
  bool Place(const Ray& r, const std::map<int64_t, Pose2>& node_poses, Placed* p) const;
  void Cover(const Placed& p, std::vector<Cell>* cells) const;

  BearingEvidenceOptions options_;
  ArrayMount mount_;
  std::vector<Ray> rays_;     // DOAs, oldest first
  std::vector<Ray> heard_;    // heard directions, oldest first
  std::vector<Cache> cache_;  // per ray of rays_ (the tail may be missing until the next solve)
};

}  // namespace sound_map
}  // namespace sarmap
