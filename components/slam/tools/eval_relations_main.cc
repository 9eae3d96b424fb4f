// sarmap-log-eval-relations: the Kümmerle et al. 2009 relation metric of an estimated
// trajectory, with a trajectory plot (PNG).

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/args.h"
#include "slam/relations.h"

using namespace sarmap;

namespace {

// Trajectory in black, each relation's error as a segment from x(t1) to x(t2) coloured from
// green (0) to red (>= 3 x mean translational error).
void Plot(const std::vector<slam::StampedPose2>& traj, const std::vector<slam::Relation>& rel,
          const slam::RelationErrors& err, const std::string& path, const std::string& title) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& p : traj) {
    x0 = std::min(x0, p.x_m), x1 = std::max(x1, p.x_m);
    y0 = std::min(y0, p.y_m), y1 = std::max(y1, p.y_m);
  }
  if (traj.empty()) x0 = y0 = 0, x1 = y1 = 1;
  const int size = 1000, margin = 40;
  const double scale = (size - 2 * margin) / std::max({x1 - x0, y1 - y0, 1e-3});
  const int w = static_cast<int>((x1 - x0) * scale) + 2 * margin;
  const int h = static_cast<int>((y1 - y0) * scale) + 2 * margin + 30;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double x, double y) {
    return cv::Point(static_cast<int>(margin + (x - x0) * scale),
                     static_cast<int>(h - margin - (y - y0) * scale));
  };
  for (size_t i = 1; i < traj.size(); ++i) {
    cv::line(img, px(traj[i - 1].x_m, traj[i - 1].y_m), px(traj[i].x_m, traj[i].y_m),
             cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  }
  const double ref = std::max(3 * err.abs_trans_m.mean, 1e-6);
  for (size_t k = 0; k < err.used_index.size(); ++k) {
    const auto& r = rel[err.used_index[k]];
    slam::StampedPose2 a, b;
    if (!slam::PoseAt(traj, r.t1_s, 1e-3, 0.5, &a) || !slam::PoseAt(traj, r.t2_s, 1e-3, 0.5, &b))
      continue;
    const double f = std::min(1.0, err.trans_errors_m[k] / ref);
    if (f < 0.34) continue;  // only the worse relations, to keep the plot readable
    cv::line(img, px(a.x_m, a.y_m), px(b.x_m, b.y_m), cv::Scalar(0, 255 * (1 - f), 255 * f), 2,
             cv::LINE_AA);
  }
  char text[256];
  std::snprintf(text, sizeof(text), "%s  trans %.4f m  rot %.3f deg  (%d relations)", title.c_str(),
                err.abs_trans_m.mean, err.abs_rot_deg.mean, err.used);
  cv::putText(img, text, cv::Point(10, 22), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write plot '" + path + "'");
}

}  // namespace

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-eval-relations", [&]() -> int {
    std::string traj_path, rel_path, plot_path, dump_path;
    double tolerance_s = 1e-3, max_gap_s = 0.5;
    common::ArgParser args(
        "sarmap-log-eval-relations",
        "Kümmerle et al. 2009 relation metric: mean +- std of absolute and squared translational "
        "and rotational errors of an estimated trajectory over a .relations file.");
    args.AddPositional("TRAJECTORY", &traj_path,
                       "estimated trajectory: 't x y yaw' lines (or TUM)");
    args.AddPositional("RELATIONS", &rel_path, "relations: 't1 t2 x y z roll pitch yaw' lines");
    args.AddFlag("--plot", &plot_path, "write a trajectory plot (PNG) here");
    args.AddFlag("--dump", &dump_path,
                 "write one line per evaluated relation: t1 t2 trans_err_m rot_err_deg x1 y1 x2 y2 "
                 "(estimated positions at t1, t2), to find where the large errors are");
    args.AddFlag("--tolerance", &tolerance_s, "time match tolerance (s)");
    args.AddFlag("--max-gap", &max_gap_s, "interpolate only between poses this close in time (s)");
    if (!args.Parse(argc, argv)) return 0;
    const auto traj = slam::LoadTrajectory(traj_path);
    const auto rel = slam::LoadRelations(rel_path);
    std::fprintf(stderr, "eval-relations: %zu poses, %zu relations\n", traj.size(), rel.size());
    slam::RelationOptions opt;
    opt.match_tolerance_s = tolerance_s;
    opt.max_gap_s = max_gap_s;
    const auto err = slam::EvaluateRelations(traj, rel, opt, [](int done, int total) {
      std::fprintf(stderr, "\reval-relations: %d / %d", done, total);
    });
    std::fprintf(stderr, "\n");
    std::cout << err.Summary();
    if (!dump_path.empty()) {
      std::FILE* f = std::fopen(dump_path.c_str(), "w");
      if (!f) throw std::runtime_error("cannot write '" + dump_path + "'");
      std::fprintf(f, "# t1 t2 trans_err_m rot_err_deg x1 y1 x2 y2\n");
      for (size_t k = 0; k < err.used_index.size(); ++k) {
        const auto& r = rel[err.used_index[k]];
        slam::StampedPose2 a, b;
        slam::PoseAt(traj, r.t1_s, tolerance_s, max_gap_s, &a);
        slam::PoseAt(traj, r.t2_s, tolerance_s, max_gap_s, &b);
        std::fprintf(f, "%.6f %.6f %.6f %.5f %.4f %.4f %.4f %.4f\n", r.t1_s, r.t2_s,
                     err.trans_errors_m[k], err.rot_errors_deg[k], a.x_m, a.y_m, b.x_m, b.y_m);
      }
      std::fclose(f);
      std::cout << "per-relation errors: " << dump_path << "\n";
    }
    if (!plot_path.empty()) {
      Plot(traj, rel, err, plot_path, traj_path.substr(traj_path.find_last_of('/') + 1));
      std::cout << "plot: " << plot_path << "\n";
    }
    return err.used > 0 ? 0 : 1;
  });
}
