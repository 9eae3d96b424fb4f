#include "mission/mission_runner.h"

#include <time.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "common/image_messages.h"
#include "common/message_conversions.h"
#include "common/time.h"
#include "common/robot_config.h"
#include "depth/depth_node_options.h"
#include "depth/depth_to_scan.h"
#include "explore/explore.h"
#include "explore/explore_node_options.h"
#include "explore/status_message.h"
#include "sim/robot.h"
#include "sim/simulator.h"
#include "slam/slam.h"
#include "slam/slam_node_options.h"

namespace sarmap {
namespace mission {

namespace {

double CpuSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

class Loop : public sim::SimSink {
 public:
  Loop(const MissionRunOptions& options, const slam::SlamOptions& slam_options,
       const explore::ExploreOptions& explore_options, const depth::DepthToScanOptions& scan_options,
       const Eigen::Isometry3d& base_from_camera, sim::Simulator* simulator, MissionObserver* observer,
       MissionResult* result)
      : options_(options),
        slam_(slam_options),
        explore_(explore_options),
        scan_options_(scan_options),
        base_from_camera_(base_from_camera),
        sim_(simulator),
        observer_(observer),
        result_(result) {}

  void Publish(const std::string&, const sarmap::odometry_t& m) override {
    slam_.AddOdometry(Seconds(m.header.utime), common::ToRigid3d(m.position_m, m.orientation).ToRigid2d());
  }

  void Publish(const std::string& channel, const sarmap::image_t& m) override {
    if (channel != "DEPTH") return;
    std::vector<uint16_t> depth_mm;
    std::string error;
    if (!common::DecodeDepthImage(m, &depth_mm, &error)) return;
    if (!converter_) {
      depth::PinholeIntrinsics in;
      in.width = m.width;
      in.height = m.height;
      in.fx = m.intrinsics.fx;
      in.fy = m.intrinsics.fy;
      in.cx = m.intrinsics.cx;
      in.cy = m.intrinsics.cy;
      converter_ = std::make_unique<depth::DepthToScan>(scan_options_, in, base_from_camera_);
    }
    const depth::PlanarScan planar = converter_->Convert(depth_mm.data(), m.depth_unit_m);
    slam::LaserScan scan;
    scan.time_s = Seconds(m.header.utime);
    scan.angle_min_rad = planar.angle_min_rad;
    scan.angle_increment_rad = planar.angle_increment_rad;
    scan.range_min_m = planar.range_min_m;
    scan.range_max_m = planar.range_max_m;
    scan.ranges_m = planar.ranges_m;
    const slam::ScanResult r = slam_.AddScan(scan);
    const double t = scan.time_s - start_s_;
    if (r.accepted) explore_.OnPose(r.map_from_base);
    if (r.accepted && t - last_map_s_ >= options_.map_period_s) {
      last_map_s_ = t;
      PublishMap(t);
    }
    explore::Scan es;
    es.angle_min_rad = scan.angle_min_rad;
    es.angle_increment_rad = scan.angle_increment_rad;
    es.range_min_m = scan.range_min_m;
    es.range_max_m = scan.range_max_m;
    es.ranges_m = scan.ranges_m;
    const double explore0 = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    const explore::Velocity v = explore_.OnScan(t, es);
    result_->explore_cpu_s += CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - explore0;
    sim_->SetVelocityCommand(v.linear_mps, v.angular_radps);
    if (t - last_status_s_ >= 0.5) {
      last_status_s_ = t;
      PublishStatus(m.header.utime, t);
    }
    slam_pose_ = r.map_from_base;
  }

  void Publish(const std::string&, const sarmap::audio_frame_t&) override {}

  void Publish(const std::string&, const sarmap::sim_truth_t& m) override {
    const double t = Seconds(m.header.utime) - start_s_;
    result_->distance_m = m.distance_m;
    result_->collisions = m.collisions;
    if (observer_) observer_->OnTruth(t, m);
    if (t - last_sample_s_ >= 1.0) {
      last_sample_s_ = t;
      MissionSample s;
      s.t_s = t;
      const common::Rigid2d truth = common::ToRigid3d(m.robot_position_m, m.robot_orientation).ToRigid2d();
      s.truth_pose = Eigen::Vector3d(truth.translation().x(), truth.translation().y(), truth.yaw_rad());
      s.slam_pose = Eigen::Vector3d(slam_pose_.translation().x(), slam_pose_.translation().y(), slam_pose_.yaw_rad());
      s.state = explore_.status().state;
      s.collisions = m.collisions;
      s.distance_m = m.distance_m;
      result_->samples.push_back(s);
    }
  }

  void Publish(const std::string&, const sarmap::occupancy_grid_t& m) override {
    if (observer_) observer_->OnFloor(Seconds(m.header.utime) - start_s_, m);
  }

  void set_start_s(double s) { start_s_ = s; }
  const explore::ExploreController& explore() const { return explore_; }
  const slam::Slam& slam() const { return slam_; }

 private:
  static double Seconds(int64_t utime) { return common::UtimeToSeconds(utime); }

  void PublishMap(double t) {
    const slam::OccupancyMap map = slam_.RenderMap();
    explore::Grid grid;
    grid.width = map.width;
    grid.height = map.height;
    grid.resolution_m = map.resolution_m;
    grid.origin_x_m = map.origin_x_m;
    grid.origin_y_m = map.origin_y_m;
    grid.cells = map.cells;
    explore_.OnMap(grid);
    if (observer_) {
      sarmap::occupancy_grid_t m;
      m.header.utime = static_cast<int64_t>((start_s_ + t) * 1e6);
      m.header.seq = map_seq_++;
      m.header.frame = "map";
      m.resolution_m = map.resolution_m;
      m.width = map.width;
      m.height = map.height;
      m.origin_x_m = map.origin_x_m;
      m.origin_y_m = map.origin_y_m;
      m.origin_yaw_rad = 0;
      m.compression = sarmap::occupancy_grid_t::COMPRESSION_NONE;
      m.data.assign(map.cells.begin(), map.cells.end());
      m.size = static_cast<int32_t>(m.data.size());
      observer_->OnMap(t, m);
    }
  }

  void PublishStatus(int64_t utime, double t) {
    const explore::ExploreStatus& s = explore_.status();
    if (s.state == "home" && result_->home_after_s < 0) result_->home_after_s = t;
    if (!observer_) return;
    sarmap::explore_status_t out = explore::ToStatusMessage(s, utime);
    out.header.seq = status_seq_++;
    observer_->OnExploreStatus(t, out);
  }

  MissionRunOptions options_;
  slam::Slam slam_;
  explore::ExploreController explore_;
  depth::DepthToScanOptions scan_options_;
  Eigen::Isometry3d base_from_camera_;
  std::unique_ptr<depth::DepthToScan> converter_;
  sim::Simulator* sim_;
  MissionObserver* observer_;
  MissionResult* result_;
  double start_s_ = 0;
  double last_map_s_ = -1e9, last_status_s_ = -1e9, last_sample_s_ = -1e9;
  int64_t map_seq_ = 0, status_seq_ = 0;
  slam::Rigid2d slam_pose_;
};

// An 8-bit greyscale image as a binary PGM, rows top first.
void WritePgm(const std::string& path, int width, int height, const std::vector<uint8_t>& image) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(f, "P5\n%d %d\n255\n", width, height);
  std::fwrite(image.data(), 1, image.size(), f);
  std::fclose(f);
}

// The explorer's grid as a PGM: unknown grey (128), free white, occupied black, free but too
// near an obstacle light grey (200), seen too little to call (uncertain) 170, the last path 60.
void WriteExplorerMap(const explore::ExploreController& controller, const std::string& path) {
  const explore::ExploreMap& map = controller.map();
  const explore::Grid& g = map.grid();
  std::vector<uint8_t> image(static_cast<size_t>(g.width) * g.height);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int8_t v = g.at(x, y);
      const auto& o = map.options();
      uint8_t c = v < 0                          ? 128
                  : v >= o.occupied_threshold    ? 0
                  : v >= o.free_threshold        ? 170
                  : map.Traversable(x, y)        ? 255
                                                 : 200;
      image[static_cast<size_t>(g.height - 1 - y) * g.width + x] = c;
    }
  }
  for (const auto& p : controller.status().path) {
    const Eigen::Vector2i c = g.CellOf(p);
    if (g.Contains(c.x(), c.y())) image[static_cast<size_t>(g.height - 1 - c.y()) * g.width + c.x()] = 60;
  }
  WritePgm(path, g.width, g.height, image);
}

// SLAM's map as a PGM: unknown grey, occupancy 0..100 from white to black.
void WriteSlamMap(const slam::Slam& slam, const std::string& path) {
  const slam::OccupancyMap map = slam.RenderMap();
  std::vector<uint8_t> image(static_cast<size_t>(map.width) * map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const int8_t v = map.cells[static_cast<size_t>(y) * map.width + x];
      image[static_cast<size_t>(map.height - 1 - y) * map.width + x] =
          v < 0 ? 128 : static_cast<uint8_t>(255 - (255 * std::min<int>(v, 100)) / 100);
    }
  }
  WritePgm(path, map.width, map.height, image);
}

}  // namespace

MissionResult RunMission(const MissionRunOptions& options, MissionObserver* observer,
                         const std::function<void(double)>& progress) {
  const double cpu0 = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
  std::vector<std::string> sim_overrides = {
      "world=" + options.world, "seed=" + std::to_string(options.seed), "drive=cmd_vel", "speed=0",
      "audio.enabled=false", "camera.rate_hz=" + std::to_string(options.camera_rate_hz), "camera.jpeg_quality=0",
      "camera.compress_depth=false"};
  sim_overrides.insert(sim_overrides.end(), options.sim_overrides.begin(), options.sim_overrides.end());
  const auto sim_options = common::LoadOptions<sim::SimOptions>(options.sim_config, sim_overrides);
  const sim::SimSetup setup = sim::LoadSetup(sim_options, sim::FindRepoRoot(options.sim_config));
  const auto slam_file = common::LoadOptions<slam::SlamNodeOptions>(options.slam_config, options.slam_overrides);
  std::vector<std::string> explore_overrides = options.explore_overrides;
  if (!options.mode.empty()) explore_overrides.push_back("explore.mode=" + options.mode);
  const auto explore_file = common::LoadOptions<explore::ExploreNodeOptions>(options.explore_config, explore_overrides);
  const auto depth_file = common::LoadOptions<depth::DepthNodeOptions>(options.depth_config, options.depth_overrides);
  const depth::DepthToScanOptions scan_options = depth_file.ScanOptions();
  const Eigen::Isometry3d base_from_camera = setup.robot.base_from_camera.ToRigid3d().ToIsometry();

  sim::Simulator simulator(setup);
  MissionResult result;
  MissionRunOptions loop_options = options;
  if (loop_options.map_period_s <= 0) loop_options.map_period_s = slam_file.map_period_s;
  Loop loop(loop_options, slam_file.slam, explore_file.explore, scan_options, base_from_camera, &simulator, observer,
            &result);
  loop.set_start_s(1e-6 * static_cast<double>(simulator.start_utime()));
  const double step_s = 0.05;
  double next_progress = 10;
  for (double t = step_s; t <= options.duration_s + 1e-9; t += step_s) {
    simulator.AdvanceTo(t, &loop);
    if (simulator.collisions() > static_cast<int>(result.contacts.size())) {
      const sim::Contact& c = simulator.last_contact();
      char text[160];
      std::snprintf(text, sizeof(text), "t=%.1f s at (%.2f, %.2f) m heading %.0f deg: %s", c.t_s,
                    c.map_from_base.translation().x(), c.map_from_base.translation().y(),
                    c.map_from_base.yaw_rad() * 180 / M_PI, c.what.c_str());
      result.contacts.resize(simulator.collisions(), text);
    }
    if (progress && t >= next_progress) {
      progress(t);
      next_progress += 10;
    }
    if (loop.explore().status().state == "home" && t > 5) {
      // Home: the mission is over; a few more seconds so that the last map is drawn.
      simulator.AdvanceTo(t + 1.0, &loop);
      result.simulated_s = t + 1.0;
      break;
    }
    result.simulated_s = t;
  }
  if (!options.explorer_map_pgm.empty()) WriteExplorerMap(loop.explore(), options.explorer_map_pgm);
  if (!options.slam_map_pgm.empty()) WriteSlamMap(loop.slam(), options.slam_map_pgm);
  result.final_state = loop.explore().status().state;
  result.recoveries = loop.explore().status().recoveries;
  result.came_home = result.final_state == "home";
  result.cpu_s = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
  return result;
}

}  // namespace mission
}  // namespace sarmap
