#pragma once
// The relation-based SLAM metric of Kümmerle et al. 2009 ("On measuring the accuracy of SLAM
// algorithms", Auton. Robots 27(4)).
//
// A relation (t1, t2, d*) is a manually verified relative pose d* = x(t1)^-1 (+) x(t2). For an
// estimated trajectory x^, the error of the relation is
//     e = d*^-1 (+) (x^(t1)^-1 (+) x^(t2))          (SE(2) compositions)
// with translational error |e.t| (m) and rotational error |e.theta| (deg); the metric reports
// mean and standard deviation of |e.t|, |e.t|^2, |e.theta| and |e.theta|^2 over all relations.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace sarmap {
namespace slam {

struct StampedPose2 {
  double time_s = 0;
  double x_m = 0, y_m = 0, yaw_rad = 0;
};

struct Relation {
  double t1_s = 0, t2_s = 0;
  double x_m = 0, y_m = 0, yaw_rad = 0;
};

struct MeanStd {
  double mean = 0, std = 0;
};

struct RelationErrors {
  MeanStd abs_trans_m, sq_trans_m2, abs_rot_deg, sq_rot_deg2;
  int used = 0;     // relations evaluated
  int missing = 0;  // relations whose times are not covered by the trajectory
  std::vector<double> trans_errors_m, rot_errors_deg;  // per used relation, in file order
  std::vector<int> used_index;                           // index into the relations
  std::string Summary() const;
};

// Relations file: "t1 t2 x y z roll pitch yaw" per line (z, roll, pitch ignored).
std::vector<Relation> LoadRelations(const std::string& path);
// Trajectory file: "t x y yaw" per line, or TUM "t x y z qx qy qz qw"; '#' comments.
std::vector<StampedPose2> LoadTrajectory(const std::string& path);
void SaveTrajectory(const std::string& path, const std::vector<StampedPose2>& trajectory);

// Pose at `time_s`: the pose stamped within `match_tolerance_s`, else interpolated between
// neighbours no more than `max_gap_s` apart. Trajectory sorted by time. False if neither.
bool PoseAt(const std::vector<StampedPose2>& trajectory, double time_s, double match_tolerance_s,
            double max_gap_s, StampedPose2* pose);

struct RelationOptions {
  double match_tolerance_s = 1e-3;  // relation files round times to 1e-5 s
  double max_gap_s = 0.5;
};

RelationErrors EvaluateRelations(std::vector<StampedPose2> trajectory,
                                 const std::vector<Relation>& relations,
                                 const RelationOptions& options = {},
                                 const std::function<void(int, int)>& progress = nullptr);

}  // namespace slam
}  // namespace sarmap
