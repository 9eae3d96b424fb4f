#include "slam/relations.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace slam {
namespace {

struct Se2 {
  double x, y, t;
};
Se2 Compose(const Se2& a, const Se2& b) {
  const double c = std::cos(a.t), s = std::sin(a.t);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, std::remainder(a.t + b.t, 2 * M_PI)};
}
Se2 Inverse(const Se2& a) {
  const double c = std::cos(a.t), s = std::sin(a.t);
  return {-c * a.x - s * a.y, s * a.x - c * a.y, -a.t};
}

MeanStd Stats(const std::vector<double>& v) {
  MeanStd r;
  if (v.empty()) return r;
  double sum = 0;
  for (double x : v) sum += x;
  r.mean = sum / v.size();
  double ss = 0;
  for (double x : v) ss += (x - r.mean) * (x - r.mean);
  r.std = v.size() > 1 ? std::sqrt(ss / (v.size() - 1)) : 0;
  return r;
}

std::vector<std::vector<double>> ReadNumbers(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  std::vector<std::vector<double>> rows;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream s(line);
    std::vector<double> row;
    std::string tok;
    while (s >> tok) {
      char* end = nullptr;
      const double v = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end) {
        throw std::runtime_error(path + ":" + std::to_string(n) + ": not a number: '" + tok + "'");
      }
      row.push_back(v);
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

std::vector<Relation> LoadRelations(const std::string& path) {
  std::vector<Relation> out;
  int n = 0;
  for (const auto& r : ReadNumbers(path)) {
    ++n;
    if (r.size() != 8) {
      throw std::runtime_error(path + ": relation " + std::to_string(n) + " has " +
                               std::to_string(r.size()) + " columns, expected 8");
    }
    out.push_back({r[0], r[1], r[2], r[3], r[7]});
  }
  return out;
}

std::vector<StampedPose2> LoadTrajectory(const std::string& path) {
  std::vector<StampedPose2> out;
  for (const auto& r : ReadNumbers(path)) {
    if (r.size() == 4) {
      out.push_back({r[0], r[1], r[2], r[3]});
    } else if (r.size() == 8) {  // TUM: t x y z qx qy qz qw
      const double yaw = std::atan2(2 * (r[7] * r[6] + r[4] * r[5]), 1 - 2 * (r[5] * r[5] + r[6] * r[6]));
      out.push_back({r[0], r[1], r[2], yaw});
    } else {
      throw std::runtime_error(path + ": trajectory lines need 4 (t x y yaw) or 8 (TUM) columns");
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedPose2& a, const StampedPose2& b) { return a.time_s < b.time_s; });
  return out;
}

void SaveTrajectory(const std::string& path, const std::vector<StampedPose2>& trajectory) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << "# t_s x_m y_m yaw_rad (map_from_base)\n" << std::fixed;
  for (const auto& p : trajectory) {
    out << std::setprecision(6) << p.time_s << ' ' << std::setprecision(6) << p.x_m << ' '
        << p.y_m << ' ' << p.yaw_rad << '\n';
  }
  if (!out) throw std::runtime_error("write failed: '" + path + "'");
}

bool PoseAt(const std::vector<StampedPose2>& traj, double t, double tol, double max_gap,
            StampedPose2* pose) {
  if (traj.empty()) return false;
  auto it = std::lower_bound(traj.begin(), traj.end(), t,
                             [](const StampedPose2& p, double v) { return p.time_s < v; });
  const StampedPose2* best = nullptr;
  if (it != traj.end() && std::abs(it->time_s - t) <= tol) best = &*it;
  if (it != traj.begin() && std::abs((it - 1)->time_s - t) <= tol &&
      (!best || std::abs((it - 1)->time_s - t) < std::abs(best->time_s - t))) {
    best = &*(it - 1);
  }
  if (best) {
    *pose = *best;
    pose->time_s = t;
    return true;
  }
  if (it == traj.end() || it == traj.begin()) return false;
  const StampedPose2& a = *(it - 1);
  const StampedPose2& b = *it;
  if (b.time_s - a.time_s > max_gap) return false;
  const double f = (t - a.time_s) / (b.time_s - a.time_s);
  pose->time_s = t;
  pose->x_m = a.x_m + f * (b.x_m - a.x_m);
  pose->y_m = a.y_m + f * (b.y_m - a.y_m);
  pose->yaw_rad = a.yaw_rad + f * std::remainder(b.yaw_rad - a.yaw_rad, 2 * M_PI);
  return true;
}

RelationErrors EvaluateRelations(std::vector<StampedPose2> traj,
                                 const std::vector<Relation>& relations,
                                 const RelationOptions& options,
                                 const std::function<void(int, int)>& progress) {
  std::stable_sort(traj.begin(), traj.end(),
                   [](const StampedPose2& a, const StampedPose2& b) { return a.time_s < b.time_s; });
  RelationErrors out;
  std::vector<double> sq_t, sq_r;
  for (size_t i = 0; i < relations.size(); ++i) {
    const Relation& r = relations[i];
    StampedPose2 p1, p2;
    if (!PoseAt(traj, r.t1_s, options.match_tolerance_s, options.max_gap_s, &p1) ||
        !PoseAt(traj, r.t2_s, options.match_tolerance_s, options.max_gap_s, &p2)) {
      ++out.missing;
      continue;
    }
    const Se2 a{p1.x_m, p1.y_m, p1.yaw_rad}, b{p2.x_m, p2.y_m, p2.yaw_rad};
    const Se2 estimated = Compose(Inverse(a), b);
    const Se2 e = Compose(Inverse(Se2{r.x_m, r.y_m, r.yaw_rad}), estimated);
    const double et = std::hypot(e.x, e.y);
    const double er = std::abs(std::remainder(e.t, 2 * M_PI)) * 180.0 / M_PI;
    out.trans_errors_m.push_back(et);
    out.rot_errors_deg.push_back(er);
    sq_t.push_back(et * et);
    sq_r.push_back(er * er);
    out.used_index.push_back(static_cast<int>(i));
    if (progress && (i % 200 == 0 || i + 1 == relations.size())) {
      progress(static_cast<int>(i + 1), static_cast<int>(relations.size()));
    }
  }
  out.used = static_cast<int>(out.trans_errors_m.size());
  out.abs_trans_m = Stats(out.trans_errors_m);
  out.sq_trans_m2 = Stats(sq_t);
  out.abs_rot_deg = Stats(out.rot_errors_deg);
  out.sq_rot_deg2 = Stats(sq_r);
  return out;
}

std::string RelationErrors::Summary() const {
  std::ostringstream s;
  s << std::fixed;
  s << "relations used " << used << ", missing " << missing << "\n";
  s << std::setprecision(4) << "abs trans [m]    " << abs_trans_m.mean << " +- " << abs_trans_m.std << "\n";
  s << std::setprecision(4) << "sq trans  [m^2]  " << sq_trans_m2.mean << " +- " << sq_trans_m2.std << "\n";
  s << std::setprecision(3) << "abs rot   [deg]  " << abs_rot_deg.mean << " +- " << abs_rot_deg.std << "\n";
  s << std::setprecision(3) << "sq rot    [deg^2] " << sq_rot_deg2.mean << " +- " << sq_rot_deg2.std << "\n";
  return s.str();
}

}  // namespace slam
}  // namespace sarmap
