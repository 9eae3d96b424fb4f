#include "sim/robot.h"

#include <algorithm>
#include <cmath>

namespace sarmap {
namespace sim {
namespace {

void AddRectangle(std::vector<Obstacle>* out, const Eigen::Vector2d& c, double yaw, double sx, double sy,
                  const std::string& what) {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw)), ay(-ax.y(), ax.x());
  const Eigen::Vector2d p[4] = {c - ax * sx / 2 - ay * sy / 2, c + ax * sx / 2 - ay * sy / 2,
                                c + ax * sx / 2 + ay * sy / 2, c - ax * sx / 2 + ay * sy / 2};
  for (int k = 0; k < 4; ++k) out->push_back({p[k], p[(k + 1) % 4], 0.0, what});
  // The inside, too (a centre placed inside collides): the capsule along the long axis whose
  // radius is half the short side and whose ends touch the short sides lies within the box;
  // what it leaves out (near the corners) is within the edges' reach.
  const Eigen::Vector2d along = sx >= sy ? ax : ay;
  const double half_core = 0.5 * std::abs(sx - sy);
  out->push_back({c - along * half_core, c + along * half_core, 0.5 * std::min(sx, sy), what});
}

}  // namespace

double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

std::vector<Obstacle> CollisionObstacles(const World& world, bool with_people) {
  std::vector<Obstacle> obstacles;
  for (const Wall& w : world.walls) {
    if (w.base_m < kRobotHeightM) obstacles.push_back({w.from, w.to, w.thickness_m / 2, w.glass ? "glass" : "wall"});
  }
  for (const Box& b : world.boxes) {
    if (b.base_m < kRobotHeightM) AddRectangle(&obstacles, b.centre, b.yaw_rad, b.size_m.x(), b.size_m.y(), "box");
  }
  for (const Table& t : world.tables) {
    const Eigen::Vector2d ax(std::cos(t.yaw_rad), std::sin(t.yaw_rad)), ay(-ax.y(), ax.x());
    for (double sx : {-1.0, 1.0}) {
      for (double sy : {-1.0, 1.0}) {
        const Eigen::Vector2d c = t.centre + ax * sx * (t.size_m.x() / 2 - t.leg_width_m) +
                                  ay * sy * (t.size_m.y() / 2 - t.leg_width_m);
        obstacles.push_back({c, c, t.leg_width_m / 2, "table leg"});
      }
    }
    if (t.height_m - t.top_thickness_m < kRobotHeightM) {
      AddRectangle(&obstacles, t.centre, t.yaw_rad, t.size_m.x(), t.size_m.y(), "table");
    }
  }
  if (with_people) {
    for (const Person& p : world.people) {
      const double r = p.posture == Posture::kLying ? 0.5 : 0.25;
      obstacles.push_back({p.position, p.position, r, "person " + p.name});
    }
  }
  return obstacles;
}

bool CircleCollides(const Eigen::Vector2d& p, double radius_m, const std::vector<Obstacle>& obstacles) {
  for (const Obstacle& o : obstacles) {
    if (SegmentDistance(p, o.a, o.b) < radius_m + o.half_width) return true;
  }
  return false;
}

Robot::Robot(const World& world, const SimOptions& options, double max_linear_mps,
             double max_angular_radps, uint64_t seed)
    : options_(options), path_(world.robot.path), path_loop_(world.robot.path_loop),
      path_speed_(world.robot.path_speed_mps), path_turn_(world.robot.path_turn_radps),
      max_v_(max_linear_mps), max_w_(max_angular_radps),
      map_from_base_(world.robot.pose.x(), world.robot.pose.y(), world.robot.pose.z()), rng_(seed) {
  obstacles_ = CollisionObstacles(world, true);
  following_path_ = options.drive != "cmd_vel" && !path_.empty();
}

void Robot::SetCommand(double linear_mps, double angular_radps, double t_s) {
  cmd_v_ = std::clamp(linear_mps, -max_v_, max_v_);
  cmd_w_ = std::clamp(angular_radps, -max_w_, max_w_);
  cmd_time_ = t_s;
  got_cmd_ = true;
}

const Obstacle* Robot::Touched(const Eigen::Vector2d& p) const {
  for (const Obstacle& o : obstacles_) {
    if (SegmentDistance(p, o.a, o.b) < options_.robot_radius_m + o.half_width) return &o;
  }
  return nullptr;
}

void Robot::FollowPath(double* v, double* w) {
  *v = 0;
  *w = 0;
  if (path_index_ >= path_.size()) return;
  const Eigen::Vector2d to = path_[path_index_] - map_from_base_.translation();
  if (to.norm() < 0.05) {
    ++path_index_;
    if (path_index_ >= path_.size() && path_loop_) path_index_ = 0;
    return;
  }
  const double error = common::WrapAngle(std::atan2(to.y(), to.x()) - map_from_base_.yaw_rad());
  if (std::abs(error) > 0.15) {  // turn on the spot first
    *w = std::clamp(2.0 * error, -path_turn_, path_turn_);
    return;
  }
  *v = std::min(path_speed_, 1.5 * to.norm() + 0.05);
  *w = std::clamp(2.0 * error, -path_turn_, path_turn_);
}

void Robot::Step(double t_s, double dt) {
  double v = 0, w = 0;
  const bool cmd_fresh = got_cmd_ && t_s - cmd_time_ <= options_.cmd_vel_timeout_s;
  if (options_.drive == "path" || (options_.drive == "auto" && !got_cmd_ && !path_.empty())) {
    following_path_ = true;
    FollowPath(&v, &w);
  } else {
    following_path_ = false;
    if (cmd_fresh) {
      v = cmd_v_;
      w = cmd_w_;
    }
  }
  v = std::clamp(v, -max_v_, max_v_);
  w = std::clamp(w, -max_w_, max_w_);
  // Wheel slip: the base moves less than the wheels turn.
  double slip = 0;
  if (options_.odometry.slip > 0 || options_.odometry.slip_noise > 0) {
    slip = std::clamp(options_.odometry.slip + options_.odometry.slip_noise * normal_(rng_), 0.0, 1.0);
  }
  const double ds = v * dt, dtheta = w * dt;
  const double true_ds = ds * (1 - slip), true_dtheta = dtheta * (1 - slip);
  const common::Rigid2d next = map_from_base_ * common::Rigid2d(true_ds, 0.0, true_dtheta);
  // Blocked by an obstacle (a robot placed overlapping one may drive out of it).
  const Obstacle* touched = std::abs(true_ds) > 0 ? Touched(next.translation()) : nullptr;
  if (touched != nullptr && !Collides(map_from_base_.translation())) {
    if (!in_contact_) {  // one contact, however many steps it is pushed against
      ++collisions_;
      last_contact_ = {t_s, map_from_base_, touched->what};
    }
    in_contact_ = true;
    linear_ = 0;
    angular_ = w;
    const common::Rigid2d turn = map_from_base_ * common::Rigid2d(0.0, 0.0, true_dtheta);
    map_from_base_ = turn;
    wheel_dtheta_ += dtheta;
    return;
  }
  if (std::abs(true_ds) > 0) in_contact_ = false;
  distance_m_ += std::abs(true_ds);
  map_from_base_ = next;
  linear_ = v;
  angular_ = w;
  wheel_ds_ += ds;
  wheel_dtheta_ += dtheta;
}

void Robot::UpdateOdometry() {
  const OdometryOptions& o = options_.odometry;
  // Random-walk errors: variances grow with the distance driven and the angle turned, so the
  // result does not depend on the ODOM rate.
  const double var_ds = o.trans_noise * o.trans_noise * std::abs(wheel_ds_);
  const double var_dtheta = o.rot_noise * o.rot_noise * std::abs(wheel_dtheta_) +
                            o.rot_per_trans_rad_per_m * o.rot_per_trans_rad_per_m * std::abs(wheel_ds_);
  const double ds = wheel_ds_ + std::sqrt(var_ds) * normal_(rng_);
  const double dtheta = wheel_dtheta_ + std::sqrt(var_dtheta) * normal_(rng_);
  // Midpoint integration of the increment.
  odom_from_base_ = odom_from_base_ * common::Rigid2d(0.0, 0.0, dtheta / 2) *
                    common::Rigid2d(ds, 0.0, dtheta / 2);
  var_xy_ += var_ds + 1e-6 * wheel_ds_ * wheel_ds_;
  var_yaw_ += var_dtheta;
  wheel_ds_ = 0;
  wheel_dtheta_ = 0;
}

}  // namespace sim
}  // namespace sarmap
