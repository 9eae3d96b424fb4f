#pragma once
// A differential-drive base: follows velocity commands or a scripted waypoint path, stops at
// obstacles, slips, and reports noisy odometry.
//
// Odometry model, per ODOM interval with wheel motion (ds, dtheta), a random walk so the
// error does not depend on the ODOM rate:
//   ds_odo     = ds + N(0, trans_noise^2 |ds|)                       (std trans_noise after 1 m)
//   dtheta_odo = dtheta + N(0, rot_noise^2 |dtheta| + rot_per_trans^2 |ds|)
// Slip: the base really moves (1 - s) of what the wheels turn, s ~ N(slip, slip_noise^2)
// clipped to [0, 1]; odometry sees the wheels, not the slip.

#include <random>
#include <vector>

#include "common/transform.h"
#include "sim/sim_options.h"
#include "sim/world.h"

namespace sarmap {
namespace sim {

struct Obstacle {  // a 2D segment with a half-width (walls, box edges, table legs)
  Eigen::Vector2d a, b;
  double half_width;
  std::string what;  // for messages: "wall", "box", "table leg", "table", "person <name>"
};

// Where and against what the base last came into contact.
struct Contact {
  double t_s = 0;
  common::Rigid2d map_from_base;
  std::string what;
};

// The base is this tall: parts of the world above it (table tops, high window bands) do not
// stop it.
constexpr double kRobotHeightM = 0.6;

// What stops the base, as segments with half-widths: walls and glass panels (their centre
// lines), boxes (four edges plus a capsule inside along the long axis, so that a centre
// placed inside one collides), table legs (points) and table tops that reach below kRobotHeightM; people as
// discs (0.25 m, lying 0.5 m) when `with_people`. A circle of radius r at p collides when
// dist(p, segment) < r + half_width for any of them.
std::vector<Obstacle> CollisionObstacles(const World& world, bool with_people);
// Distance from p to the segment [a, b].
double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b);
// Whether a circle of `radius_m` at p touches any obstacle (the robot's collision test).
bool CircleCollides(const Eigen::Vector2d& p, double radius_m, const std::vector<Obstacle>& obstacles);

class Robot {
 public:
  Robot(const World& world, const SimOptions& options, double max_linear_mps,
        double max_angular_radps, uint64_t seed);

  void SetCommand(double linear_mps, double angular_radps, double t_s);
  // Advances by dt: path following or commands per options.drive.
  void Step(double t_s, double dt_s);
  // The odometry increment since the last call, with noise, integrated into odom_from_base.
  void UpdateOdometry();

  const common::Rigid2d& map_from_base() const { return map_from_base_; }
  const common::Rigid2d& odom_from_base() const { return odom_from_base_; }
  double linear_mps() const { return linear_; }
  double angular_radps() const { return angular_; }
  double odom_var_xy() const { return var_xy_; }
  double odom_var_yaw() const { return var_yaw_; }
  // Contacts with obstacles: a blocked motion counts once until the robot moves freely again.
  int collisions() const { return collisions_; }
  // The contact that counted last (valid when collisions() > 0).
  const Contact& last_contact() const { return last_contact_; }
  double distance_m() const { return distance_m_; }  // true path length driven
  bool following_path() const { return following_path_; }

 private:
  // The obstacle a base at p touches, or nullptr.
  const Obstacle* Touched(const Eigen::Vector2d& p) const;
  bool Collides(const Eigen::Vector2d& p) const { return Touched(p) != nullptr; }
  void FollowPath(double* v, double* w);

  SimOptions options_;
  std::vector<Obstacle> obstacles_;
  std::vector<Eigen::Vector2d> path_;
  size_t path_index_ = 0;
  bool path_loop_ = false;
  double path_speed_, path_turn_;
  double max_v_, max_w_;
  common::Rigid2d map_from_base_, odom_from_base_;
  double cmd_v_ = 0, cmd_w_ = 0, cmd_time_ = -1e9;
  bool got_cmd_ = false;
  bool following_path_ = false;
  double linear_ = 0, angular_ = 0;
  double wheel_ds_ = 0, wheel_dtheta_ = 0;  // since the last odometry update
  double var_xy_ = 0, var_yaw_ = 0;
  int collisions_ = 0;
  Contact last_contact_;
  bool in_contact_ = false;
  double distance_m_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace sim
}  // namespace sarmap
