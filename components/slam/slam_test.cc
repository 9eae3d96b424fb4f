// SLAM core behaviour: the relations metric, the CARMEN reader, input rejection, save/load
// resume, and a real-data regression on a short prefix of the Intel log.

#include "slam/slam.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>

#include "common/state_file.h"
#include "slam/carmen.h"
#include "slam/map_io.h"
#include "slam/relations.h"

// Measured on this prefix (see the printout), with a margin.
#define REL_TRANS_BOUND 0.06
#define REL_ROT_BOUND 0.6

namespace sarmap {
namespace slam {
namespace {

const std::string kIntel = std::string(SARMAP_DATA_DIR) + "/slam/intel/intel.log";
const std::string kIntelRelations = std::string(SARMAP_DATA_DIR) + "/slam/intel/intel.relations";

TEST(RelationsTest, MetricOfAKnownError) {
  // Truth: straight line, 1 m steps. Estimate: every step 1.1 m and turned by 1 deg.
  std::vector<StampedPose2> est;
  std::vector<Relation> rel;
  double x = 0, y = 0, yaw = 0;
  const double turn = M_PI / 180;
  for (int i = 0; i < 10; ++i) {
    est.push_back({double(i), x, y, yaw});
    x += 1.1 * std::cos(yaw);
    y += 1.1 * std::sin(yaw);
    yaw += turn;
    if (i < 9) rel.push_back({double(i), double(i + 1), 1.0, 0.0, 0.0});
  }
  const RelationErrors e = EvaluateRelations(est, rel);
  EXPECT_EQ(e.used, 9);
  EXPECT_EQ(e.missing, 0);
  // e = d*^-1 (+) d_est = (1.1 - 1, 0, 1 deg): 0.1 m and 1 deg for every relation.
  EXPECT_NEAR(e.abs_trans_m.mean, 0.1, 1e-9);
  EXPECT_NEAR(e.abs_trans_m.std, 0.0, 1e-9);
  EXPECT_NEAR(e.sq_trans_m2.mean, 0.01, 1e-9);
  EXPECT_NEAR(e.abs_rot_deg.mean, 1.0, 1e-9);
  EXPECT_NEAR(e.sq_rot_deg2.mean, 1.0, 1e-9);
  // A relation outside the trajectory is counted as missing.
  rel.push_back({100, 101, 1, 0, 0});
  EXPECT_EQ(EvaluateRelations(est, rel).missing, 1);
}

TEST(CarmenTest, ParsesTheLineTypesAndCountsMalformedLines) {
  std::istringstream in(
      "# comment\n"
      "PARAM robot_length 0.5 host 0\n"
      "ODOM 1.0 2.0 0.5 0.1 0.2 0 100.5 host 100.5\n"
      "FLASER 3 1.0 2.0 3.0 9 9 9 1.5 2.5 0.25 100.6 host 0.1\n"
      "RAWLASER1 0 -1.5 3.0 0.01 80 0.01 0 2 4.0 5.0 0 100.7 host 100.7\n"
      "ROBOTLASER1 0 -1.5 3.0 0.01 80 0.01 0 1 7.0 0 1.1 0.0 0.0 1.0 0.0 0.0 0 0 0 0 0 100.8 host "
      "1\n"
      "ODOM 1.0 oops\n");
  CarmenReader reader;
  std::vector<CarmenOdometry> odom;
  std::vector<CarmenLaser> lasers;
  reader.on_odometry = [&](const CarmenOdometry& o) { odom.push_back(o); };
  reader.on_laser = [&](const CarmenLaser& l) { lasers.push_back(l); };
  const CarmenStats s = reader.Read(in);
  EXPECT_EQ(s.odometry, 1);
  EXPECT_EQ(s.lasers, 3);
  EXPECT_EQ(s.malformed, 1);
  EXPECT_EQ(s.skipped_unknown, 1);
  ASSERT_EQ(odom.size(), 1u);
  EXPECT_DOUBLE_EQ(odom[0].time_s, 100.5);
  ASSERT_EQ(lasers.size(), 3u);
  EXPECT_EQ(lasers[0].source, "FLASER");
  EXPECT_TRUE(lasers[0].has_odometry);
  EXPECT_DOUBLE_EQ(lasers[0].odometry.theta_rad, 0.25);
  EXPECT_NEAR(lasers[0].angle_increment_rad, M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(lasers[1].time_s, 100.7);
  EXPECT_EQ(lasers[1].ranges_m.size(), 2u);
  // ROBOTLASER1: laser 0.1 m ahead of the robot.
  EXPECT_NEAR(lasers[2].base_from_laser_x_m, 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(lasers[2].time_s, 100.8);
}

TEST(CarmenTest, LinesWithTheirOwnGeometryReadAsWritten) {
  // Interlaced SICK lines: each RAWLASER1 line has its own start angle and beam count.
  std::istringstream in(
      "RAWLASER1 0 -1.5707963 3.1415927 0.0174533 81.9 0.01 0 3 1.0 2.0 3.0 0 10.0 host 10.0\n"
      "RAWLASER1 0 -1.5664330 3.1241393 0.0174533 81.9 0.01 0 2 4.0 5.0 0 10.1 host 10.1\n");
  CarmenReader reader;
  std::vector<CarmenLaser> lasers;
  reader.on_laser = [&](const CarmenLaser& l) { lasers.push_back(l); };
  reader.Read(in);
  ASSERT_EQ(lasers.size(), 2u);
  EXPECT_NEAR(lasers[0].angle_min_rad, -M_PI / 2, 1e-7);
  EXPECT_NEAR(lasers[1].angle_min_rad, -89.75 * M_PI / 180, 1e-7);
  EXPECT_EQ(lasers[0].ranges_m.size(), 3u);
  EXPECT_EQ(lasers[1].ranges_m.size(), 2u);

  // Each written line reads back to the same geometry, readings, odometry and laser pose.
  CarmenLaser robot = lasers[0];
  robot.source = "ROBOTLASER1";
  robot.has_odometry = true;
  robot.odometry = {10.0, 1.0, 2.0, 0.5, 0.0, 0.0};
  robot.base_from_laser_x_m = 0.2;
  robot.base_from_laser_yaw_rad = 0.1;
  CarmenOdometry odom{10.0, 1.0, 2.0, 0.5, 0.3, 0.1};
  std::istringstream back(FormatCarmenOdometry(odom) + "\n" + FormatCarmenLaser(lasers[1]) + "\n" +
                          FormatCarmenLaser(robot) + "\n");
  std::vector<CarmenOdometry> odom_back;
  std::vector<CarmenLaser> back_lasers;
  reader.on_odometry = [&](const CarmenOdometry& o) { odom_back.push_back(o); };
  reader.on_laser = [&](const CarmenLaser& l) { back_lasers.push_back(l); };
  const CarmenStats s = reader.Read(back);
  EXPECT_EQ(s.malformed, 0);
  ASSERT_EQ(odom_back.size(), 1u);
  EXPECT_NEAR(odom_back[0].theta_rad, 0.5, 1e-6);
  EXPECT_NEAR(odom_back[0].rv_radps, 0.1, 1e-6);
  EXPECT_DOUBLE_EQ(odom_back[0].time_s, 10.0);
  ASSERT_EQ(back_lasers.size(), 2u);
  EXPECT_EQ(back_lasers[0].source, "RAWLASER1");
  EXPECT_NEAR(back_lasers[0].angle_min_rad, lasers[1].angle_min_rad, 1e-9);
  EXPECT_NEAR(back_lasers[0].angle_increment_rad, lasers[1].angle_increment_rad, 1e-9);
  EXPECT_EQ(back_lasers[0].ranges_m, lasers[1].ranges_m);
  EXPECT_DOUBLE_EQ(back_lasers[0].time_s, 10.1);
  EXPECT_EQ(back_lasers[1].source, "ROBOTLASER1");
  EXPECT_NEAR(back_lasers[1].odometry.theta_rad, 0.5, 1e-6);
  EXPECT_NEAR(back_lasers[1].base_from_laser_x_m, 0.2, 1e-5);
  EXPECT_NEAR(back_lasers[1].base_from_laser_yaw_rad, 0.1, 1e-5);
}

TEST(CarmenTest, InterlacingKeepsEachReadingAtItsAngle) {
  CarmenLaser l;
  l.angle_min_rad = -1.0;
  l.angle_increment_rad = 0.1;
  l.ranges_m = {0, 1, 2, 3, 4, 5, 6};  // reading i = i: its angle is -1 + 0.1 i
  const size_t expected_counts[kInterlacePhases] = {7, 6, 4, 3};
  for (int phase = 0; phase < kInterlacePhases; ++phase) {
    const CarmenLaser c = InterlacedLaser(l, phase);
    ASSERT_EQ(c.ranges_m.size(), expected_counts[phase]) << phase;
    for (size_t j = 0; j < c.ranges_m.size(); ++j) {
      const double angle = c.angle_min_rad + j * c.angle_increment_rad;
      EXPECT_NEAR(angle, -1.0 + 0.1 * c.ranges_m[j], 1e-12) << "phase " << phase << " beam " << j;
    }
  }
  EXPECT_EQ(InterlacedLaser(l, 5).ranges_m.size(), 6u);  // phase 5 % 4 = 1
}

LaserScan MakeScan(double t, int n = 180) {
  LaserScan s;
  s.time_s = t;
  s.angle_min_rad = -M_PI / 2;
  s.angle_increment_rad = M_PI / (n - 1);
  s.range_min_m = 0;
  s.range_max_m = 30;
  s.ranges_m.assign(n, 3.0f);
  return s;
}

TEST(SlamInputTest, GarbageScansAndOdometryJumpsAreRejectedAndCounted) {
  Slam slam{SlamOptions()};
  EXPECT_TRUE(slam.AddOdometry(0.0, Rigid2d(0, 0, 0)));
  EXPECT_TRUE(slam.AddScan(MakeScan(0.0)).accepted);
  LaserScan nan_scan = MakeScan(0.1);
  nan_scan.ranges_m[10] = std::nanf("");
  EXPECT_FALSE(slam.AddScan(nan_scan).accepted);
  LaserScan negative = MakeScan(0.2);
  negative.ranges_m[3] = -1.0f;
  EXPECT_FALSE(slam.AddScan(negative).accepted);
  LaserScan one_beam = MakeScan(0.3);
  one_beam.ranges_m.resize(1);
  EXPECT_FALSE(slam.AddScan(one_beam).accepted);
  LaserScan bad_angles = MakeScan(0.4);
  bad_angles.angle_increment_rad = std::nan("");
  EXPECT_FALSE(slam.AddScan(bad_angles).accepted);
  EXPECT_EQ(slam.stats().rejected_scans, 4);
  // +inf is "no return", not garbage.
  LaserScan inf_scan = MakeScan(0.5);
  inf_scan.ranges_m[0] = INFINITY;
  EXPECT_TRUE(slam.AddScan(inf_scan).accepted);
  // Odometry: a 5 m jump in 0.1 s is rejected; normal motion is not; a jump that persists
  // (an odometry reset) is accepted as a new odometry segment after one rejection.
  EXPECT_TRUE(slam.AddOdometry(0.1, Rigid2d(0.02, 0, 0)));
  EXPECT_FALSE(slam.AddOdometry(0.2, Rigid2d(5.0, 0, 0)));
  EXPECT_TRUE(slam.AddOdometry(0.3, Rigid2d(0.05, 0, 0)));
  EXPECT_FALSE(slam.AddOdometry(0.4, Rigid2d(0.05, 0, 2.0)));  // 115 deg in 0.1 s
  EXPECT_FALSE(slam.AddOdometry(0.5, Rigid2d(std::nan(""), 0, 0)));
  EXPECT_EQ(slam.stats().rejected_odometry, 3);
  EXPECT_FALSE(slam.AddOdometry(0.6, Rigid2d(10.0, 0, 0)));
  EXPECT_TRUE(slam.AddOdometry(0.7, Rigid2d(10.01, 0, 0)));  // reset confirmed
  EXPECT_EQ(slam.stats().rejected_odometry, 4);
}

// Range from (x, y) along `angle` to the walls of the room [-5, 5] x [-3, 3] (from inside).
float RoomRange(double x, double y, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  double r = 1e9;
  if (c > 1e-9) r = std::min(r, (5 - x) / c);
  if (c < -1e-9) r = std::min(r, (-5 - x) / c);
  if (s > 1e-9) r = std::min(r, (3 - y) / s);
  if (s < -1e-9) r = std::min(r, (-3 - y) / s);
  return static_cast<float>(r);
}

// A SICK-like scanner driven through the room on an S-shaped path (x from -3 to 3 m, y and
// heading swinging); odometry overestimates distance by 5 % and heading by 2 %.
struct ScannerRun {
  bool interlace = false;          // scan k: phase k % 4 (below); else always phase 0
  bool fixed_start_angle = false;  // give every scan phase 0's start angle (a fixed table)
  Rigid2d base_from_laser;         // where the laser really is
  bool scans_carry_laser_pose = false;
  bool options_carry_laser_pose = false;
};
// Interlaced phases: 181 beams from -90 deg, then 180 beams from -89.75, -89.5, -89.25 deg, all
// 1 deg apart. Returns the largest position error (m) against the truth, and the trajectory and
// the largest heading error (deg).
double ScannerError(const ScannerRun& run, std::vector<StampedPose2>* trajectory = nullptr,
                    double* heading_error_deg = nullptr) {
  SlamOptions options;
  if (run.options_carry_laser_pose) {
    options.scan.laser_x_m = run.base_from_laser.translation().x();
    options.scan.laser_y_m = run.base_from_laser.translation().y();
    options.scan.laser_yaw_rad = run.base_from_laser.yaw_rad();
  }
  Slam slam{options};
  const int kScans = 200;
  std::vector<Rigid2d> truth;
  for (int k = 0; k < kScans; ++k) {
    const double t = 0.1 * k;
    const double x = -3.0 + 0.03 * k, y = std::sin(0.03 * k);
    const double yaw = std::atan2(0.03 * std::cos(0.03 * k), 0.03);
    truth.emplace_back(x, y, yaw);
    slam.AddOdometry(t, Rigid2d(-3.0 + 1.05 * (x + 3.0), 1.05 * y, 1.02 * yaw));
    const int phase = run.interlace ? k % 4 : 0;
    LaserScan scan;
    scan.time_s = t;
    scan.angle_min_rad = (-90.0 + 0.25 * phase) * M_PI / 180;
    scan.angle_increment_rad = M_PI / 180;
    scan.range_min_m = 0;
    scan.range_max_m = 30;
    scan.ranges_m.resize(phase == 0 ? 181 : 180);
    const Rigid2d map_from_laser = truth.back() * run.base_from_laser;
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      scan.ranges_m[i] =
          RoomRange(map_from_laser.translation().x(), map_from_laser.translation().y(),
                    map_from_laser.yaw_rad() + scan.angle_min_rad + i * scan.angle_increment_rad);
    }
    if (run.fixed_start_angle) scan.angle_min_rad = -M_PI / 2;
    scan.has_base_from_laser = run.scans_carry_laser_pose;
    scan.base_from_laser = run.base_from_laser;
    const ScanResult r = slam.AddScan(scan);
    EXPECT_TRUE(r.accepted) << "scan " << k << ": " << r.reason;
  }
  slam.Optimise();
  EXPECT_EQ(slam.stats().rejected_scans, 0);
  const auto traj = slam.Trajectory();
  EXPECT_EQ(static_cast<int>(traj.size()), kScans);
  if (trajectory) *trajectory = traj;
  const Rigid2d map_from_world = truth.front().inverse();  // the map frame: the first scan
  double worst = 0, worst_deg = 0;
  for (size_t k = 0; k < traj.size() && k < truth.size(); ++k) {
    const Rigid2d expected = map_from_world * truth[k];
    worst = std::max(worst, std::hypot(traj[k].x_m - expected.translation().x(),
                                       traj[k].y_m - expected.translation().y()));
    worst_deg = std::max(
        worst_deg,
        std::abs(std::remainder(traj[k].yaw_rad - expected.yaw_rad(), 2 * M_PI)) * 180 / M_PI);
  }
  if (heading_error_deg) *heading_error_deg = worst_deg;
  return worst;
}

TEST(SlamInputTest, AnInterlacingScannerIsTrackedWithEveryScansOwnGeometry) {
  // Every scan is used (a fixed beam count rejected three of four: "scan has 180 ranges, the
  // sensor gives 181"), and each scan's beams lie at its own angles: with the first scan's
  // start angle for all (a precomputed beam table), three of four scans turn by 0.25-0.75 deg.
  ScannerRun run;
  run.interlace = true;
  double own_deg = 0, fixed_deg = 0;
  const double own_m = ScannerError(run, nullptr, &own_deg);
  run.fixed_start_angle = true;
  const double fixed_m = ScannerError(run, nullptr, &fixed_deg);
  std::printf(
      "interlaced scanner: largest error %.4f m, %.3f deg with each scan's geometry; "
      "%.4f m, %.3f deg with one start angle for all\n",
      own_m, own_deg, fixed_m, fixed_deg);
  EXPECT_LT(own_m, 0.05);
  EXPECT_LT(own_deg, 1.0);
  EXPECT_GT(fixed_deg, 2 * own_deg);
}

TEST(SlamInputTest, AScanCarryingItsLaserPoseIsPlacedWithIt) {
  // The laser 0.3 m ahead of the base, turned by 0.2 rad. A scan that carries this pose (CARMEN
  // ROBOTLASER1 lines do) is placed exactly as with the pose in the options.
  ScannerRun run;
  run.base_from_laser = Rigid2d(0.3, 0, 0.2);
  run.scans_carry_laser_pose = true;
  std::vector<StampedPose2> carried, configured;
  const double carried_m = ScannerError(run, &carried);
  run.scans_carry_laser_pose = false;
  run.options_carry_laser_pose = true;
  const double configured_m = ScannerError(run, &configured);
  run.options_carry_laser_pose = false;
  const double ignored_m = ScannerError(run);
  std::printf(
      "laser 0.3 m ahead, 0.2 rad: largest position error %.4f m carried by the scans, "
      "%.4f m in the options, %.4f m ignored\n",
      carried_m, configured_m, ignored_m);
  ASSERT_EQ(carried.size(), configured.size());
  for (size_t k = 0; k < carried.size(); ++k) {
    EXPECT_NEAR(carried[k].x_m, configured[k].x_m, 1e-9) << k;
    EXPECT_NEAR(carried[k].yaw_rad, configured[k].yaw_rad, 1e-9) << k;
  }
  EXPECT_GT(ignored_m, 2 * carried_m);
}

TEST(SlamInputTest, ScansStampedEarlierThanThePreviousOneAreTakenInArrivalOrder) {
  // A robot drives along x at 0.05 m per scan (0.1 s). Scans 20-24 and their odometry are
  // stamped 0.75 s too early, as in the Intel log's bursts, but arrive in recording order.
  // They must be placed where they were made (processed at the newest input time, with the
  // newest odometry) and keep their own stamps in the trajectory.
  Slam slam{SlamOptions()};
  std::vector<std::pair<double, double>> stamp_and_true_x;
  for (int k = 0; k < 40; ++k) {
    const double x = -2.0 + 0.05 * k;
    const double stamp = 0.1 * k - (k >= 20 && k < 25 ? 0.75 : 0.0);
    slam.AddOdometry(stamp, Rigid2d(x, 0, 0));
    LaserScan scan = MakeScan(stamp);
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      scan.ranges_m[i] = RoomRange(x, 0, scan.angle_min_rad + i * scan.angle_increment_rad);
    }
    ASSERT_TRUE(slam.AddScan(scan).accepted) << k;
    stamp_and_true_x.emplace_back(stamp, x);
  }
  EXPECT_EQ(slam.stats().reordered_scans, 5);
  const auto traj = slam.Trajectory();
  ASSERT_EQ(traj.size(), 40u);
  for (const auto& [stamp, x] : stamp_and_true_x) {
    const auto it = std::find_if(traj.begin(), traj.end(), [&](const StampedPose2& p) {
      return std::abs(p.time_s - stamp) < 1e-9;
    });
    ASSERT_NE(it, traj.end()) << stamp;
    // The map frame starts at the first scan (x = -2).
    EXPECT_NEAR(it->x_m, x + 2.0, 0.05) << "scan stamped " << stamp;
    EXPECT_NEAR(it->y_m, 0.0, 0.05) << "scan stamped " << stamp;
  }
}

// A scan that sees only a long wall at y = 1 m on the robot's left: nothing pins x.
LaserScan WallOnlyScan(double t) {
  LaserScan scan = MakeScan(t);
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double a = scan.angle_min_rad + i * scan.angle_increment_rad;
    scan.ranges_m[i] = std::sin(a) > 0.05 ? static_cast<float>(1.0 / std::sin(a)) : INFINITY;
  }
  return scan;
}

// Drives 1 m along the wall, then stands still for 10 s while its odometry repeats the last
// reading (at half the scan rate). Returns the distance SLAM says the robot travelled while it
// stood still.
double DriftWhileStopped(bool unchanged_odometry_means_stopped) {
  SlamOptions o;
  o.local.unchanged_odometry_means_stopped = unchanged_odometry_means_stopped;
  Slam slam{o};
  double t = 0;
  for (int k = 0; k <= 20; ++k, t += 0.1) {
    slam.AddOdometry(t, Rigid2d(0.05 * k, 0, 0));
    EXPECT_TRUE(slam.AddScan(WallOnlyScan(t)).accepted);
  }
  const double stop_x = slam.Trajectory().back().x_m;
  for (int k = 0; k < 100; ++k, t += 0.1) {
    // Odometry at half the scan rate: every other scan is ahead of the newest reading.
    if (k % 2 == 0) slam.AddOdometry(t, Rigid2d(1.0, 0, 0));
    EXPECT_TRUE(slam.AddScan(WallOnlyScan(t)).accepted);
  }
  return std::abs(slam.Trajectory().back().x_m - stop_x);
}

TEST(SlamInputTest, ARobotStandingStillInAFeaturelessViewStaysWhereItStopped) {
  // The wall cannot tell the matcher that the robot stopped. Read as a stale stream, the repeated
  // odometry hands the prediction to a constant-velocity model, which drives the robot on by a
  // step (right for CARMEN logs that freeze odometry while moving); read as "stopped", it stays.
  EXPECT_LT(DriftWhileStopped(true), 0.005);
  EXPECT_GT(DriftWhileStopped(false), 0.025);
}

// Range from (x, y) along `angle` to a square pillar of half-width h centred at (cx, cy) (slab
// method), or infinity.
float PillarRange(double x, double y, double angle, double cx, double cy, double h) {
  const double d[2] = {std::cos(angle), std::sin(angle)}, o[2] = {x, y}, c[2] = {cx, cy};
  double t_near = -1e9, t_far = 1e9;
  for (int i = 0; i < 2; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (std::abs(o[i] - c[i]) > h) return INFINITY;
      continue;
    }
    double t1 = (c[i] - h - o[i]) / d[i], t2 = (c[i] + h - o[i]) / d[i];
    if (t1 > t2) std::swap(t1, t2);
    t_near = std::max(t_near, t1);
    t_far = std::min(t_far, t2);
  }
  return t_near <= t_far && t_near > 0 ? static_cast<float>(t_near) : INFINITY;
}

// A square pillar of half-width half_m centred at (x_m, 1.5) in the room; from robot positions
// x >= seen_below_x the beams that would hit it read nothing (0: a depth camera looking over a
// low object close by).
struct Pillar {
  bool present = false;
  double x_m = -1, half_m = 0.2;
  double seen_below_x = INFINITY;
  // Open windows in the wall y = 3: 0.4 m wide, centred at these x, with nothing behind them in
  // range (the beams through them return nothing: free-space rays).
  std::vector<double> windows_x;
};

// Step k of a robot driving back and forth along y = 0 in the room (x from -3 to 1 m and back,
// 0.05 m a step) with a full 360-beam scan: odometry and the scan into `slam`.
ScanResult BackAndForthStep(Slam* slam, int k, const Pillar& pillar) {
  const double phase = std::fmod(0.05 * k, 8.0);
  const double x = -3.0 + (phase < 4.0 ? phase : 8.0 - phase);
  const double t = 0.1 * k;
  slam->AddOdometry(t, Rigid2d(x, 0, 0));
  LaserScan scan = MakeScan(t, 360);
  scan.angle_min_rad = -M_PI;
  scan.angle_increment_rad = 2 * M_PI / 360;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double angle = scan.angle_min_rad + i * scan.angle_increment_rad;
    scan.ranges_m[i] = RoomRange(x, 0, angle);
    const double at_wall_x = x + scan.ranges_m[i] * std::cos(angle);
    const bool on_top_wall = std::abs(scan.ranges_m[i] * std::sin(angle) - 3.0) < 1e-4;
    for (double window_x : pillar.windows_x) {
      if (on_top_wall && std::abs(at_wall_x - window_x) < 0.2) scan.ranges_m[i] = INFINITY;
    }
    const float to_pillar =
        pillar.present ? PillarRange(x, 0, angle, pillar.x_m, 1.5, pillar.half_m) : INFINITY;
    if (to_pillar < scan.ranges_m[i]) {
      scan.ranges_m[i] = x < pillar.seen_below_x ? to_pillar : 0.0f;
    }
  }
  return slam->AddScan(scan);
}

// With `pillar`, a 0.4 m pillar stands at (-1, 1.5).
ScanResult BackAndForthStep(Slam* slam, int k, bool pillar = false) {
  Pillar p;
  p.present = pillar;
  return BackAndForthStep(slam, k, p);
}

TEST(SlamInputTest, AnOptimisationSaysWhetherItHadNewLoopClosures) {
  // A robot drives back and forth along x in the room; small submaps finish early, so the return
  // legs close loops against them. SLAM_ANCHORS carries this flag to the sound map, which applies
  // anchors only after loop closures: a flag that is never set silently turns anchors off.
  SlamOptions o;
  o.local.scans_per_submap = 10;
  o.local.node_max_distance_m = 0.1;
  o.graph.optimise_every_n_nodes = 10;
  o.loop.sampling_ratio = 1.0;
  Slam slam{o};
  int optimisations = 0, with_closures = 0;
  int64_t closures_at_last = 0;
  for (int k = 0; k < 400; ++k) {
    const ScanResult r = BackAndForthStep(&slam, k);
    ASSERT_TRUE(r.accepted);
    if (!r.optimised) continue;
    ++optimisations;
    EXPECT_EQ(r.loop_closed, slam.stats().loop_closures > closures_at_last) << "scan " << k;
    with_closures += r.loop_closed;
    closures_at_last = slam.stats().loop_closures;
  }
  EXPECT_GT(optimisations, 3);
  EXPECT_GT(with_closures, 0);
}

// Turns in place at 0.5 rad/s in the room (scans at 30 Hz, odometry at 20 Hz, a scan is
// processed before the reading after it) with the robot's strong rotation prior; returns the
// largest heading error (deg).
double LargestHeadingErrorInATurn(double odometry_extrapolation_s) {
  SlamOptions o;
  o.local.ceres_rotation_prior_from_prediction = true;
  o.local.ceres_rotation_weight = 1000;
  o.local.correlative_angular_window_deg = 0.5;  // a scan that cannot pin its heading by search
  o.local.odometry_extrapolation_s = odometry_extrapolation_s;
  Slam slam{o};
  double worst_deg = 0;
  int next_odom = 0;
  for (int k = 0; k < 90; ++k) {
    const double t = k / 30.0;
    for (; next_odom / 20.0 <= t + 1e-9; ++next_odom) {
      slam.AddOdometry(next_odom / 20.0, Rigid2d(0, 0, 0.5 * next_odom / 20.0));
    }
    LaserScan scan = MakeScan(t, 360);
    scan.angle_min_rad = -M_PI / 4;
    scan.angle_increment_rad = (M_PI / 2) / 359;
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      scan.ranges_m[i] =
          RoomRange(0, 0, 0.5 * t + scan.angle_min_rad + i * scan.angle_increment_rad);
    }
    const ScanResult r = slam.AddScan(scan);
    EXPECT_TRUE(r.accepted);
    if (k < 3) continue;  // the first readings: nothing to extrapolate from yet
    worst_deg = std::max(
        worst_deg,
        std::abs(std::remainder(r.map_from_base.yaw_rad() - 0.5 * t, 2 * M_PI)) * 180 / M_PI);
  }
  return worst_deg;
}

TEST(SlamInputTest, ScansBetweenOdometryReadingsInATurnAreExtrapolated) {
  // Held, the last reading is 1/60 or 1/30 s old, 0.5 or 1 deg behind at 0.5 rad/s; the strong
  // rotation prior keeps the match near that prediction.
  EXPECT_GT(LargestHeadingErrorInATurn(0.0), 0.4);
  EXPECT_LT(LargestHeadingErrorInATurn(0.1), 0.05);
}

TEST(SlamInputTest, AfterARestartScansWaitForTheOdometryThatBridgesTheGap) {
  // The robot drives at 0.05 m per scan along a corridor whose walls (y = +-1.5 m) cannot tell
  // where along it the robot is. SLAM saves at scan 20 and comes back at scan 30, 0.5 m further
  // on; its first two scans arrive before any odometry. Placed anyway, they are predicted at
  // the saved pose, 0.5 m behind; in the simulated lab the matcher then moved them part of the
  // way and the bridge was added on top (0.5-1 m off, sarmap-slam-offline replay of a kill -9).
  auto scan_at = [](int k) {
    LaserScan scan = MakeScan(0.1 * k);
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      const double s = std::sin(scan.angle_min_rad + i * scan.angle_increment_rad);
      scan.ranges_m[i] = std::abs(s) > 0.05 ? static_cast<float>(1.5 / std::abs(s)) : INFINITY;
    }
    return scan;
  };
  Slam first{SlamOptions()};
  for (int k = 0; k <= 20; ++k) {
    first.AddOdometry(0.1 * k, Rigid2d(0.05 * k, 0, 0));
    ASSERT_TRUE(first.AddScan(scan_at(k)).accepted);
  }
  const std::string path = ::testing::TempDir() + "/slam_resume_before_odometry.pg";
  first.Save(path);
  Slam resumed{SlamOptions()};
  resumed.Load(path);
  for (int k : {30, 31}) {
    const ScanResult r = resumed.AddScan(scan_at(k));
    EXPECT_FALSE(r.accepted);
    EXPECT_TRUE(r.waiting_for_odometry);
  }
  EXPECT_EQ(resumed.stats().scans_waiting_for_odometry, 2);
  for (int k = 32; k <= 40; ++k) {
    resumed.AddOdometry(0.1 * k, Rigid2d(0.05 * k, 0, 0));
    ASSERT_TRUE(resumed.AddScan(scan_at(k)).accepted);
  }
  // The robot has driven 2.0 m since the first scan (the map's origin).
  EXPECT_NEAR(resumed.CurrentPose().translation().x(), 2.0, 0.05);
  EXPECT_NEAR(resumed.CurrentPose().translation().y(), 0.0, 0.05);
}

// The back-and-forth drive for `cycles` cycles (160 steps each: 4 m out and back) with small
// submaps and every loop searched; `trim` on or off.
SlamOptions BackAndForthOptions(bool trim) {
  SlamOptions o;
  o.local.scans_per_submap = 10;
  o.local.node_max_distance_m = 0.1;
  o.graph.optimise_every_n_nodes = 10;
  o.loop.sampling_ratio = 1.0;
  o.loop.linear_window_m = 1.0;  // the drift here is centimetres
  o.trim.enabled = trim;
  return o;
}

// Largest distance of the trajectory from the drive's truth (x from -3 to 1 m on y = 0; the map
// frame is the first scan's pose).
double BackAndForthError(const Slam& slam) {
  double worst = 0;
  const auto traj = slam.Trajectory();
  for (size_t k = 0; k < traj.size(); ++k) {
    const double phase = std::fmod(0.05 * k, 8.0);
    const double x = phase < 4.0 ? phase : 8.0 - phase;
    worst = std::max(worst, std::hypot(traj[k].x_m - x, traj[k].y_m));
  }
  return worst;
}

TEST(SlamTrimTest, RevisitingTheSameRoomKeepsTheGraphTheSizeOfTheRoom) {
  // Every 360-degree scan sees the whole room, so each pass covers all that the passes before
  // it mapped. Without trimming the graph grows with every pass; with it, the live submaps and
  // nodes after 4 and after 8 passes are the same few, the trajectory stays on the truth and
  // the latest node's covariance (one factorisation of the trimmed graph) is still computable.
  Slam plain{BackAndForthOptions(false)};
  Slam trimmed{BackAndForthOptions(true)};
  int live_nodes_at_4 = 0, live_submaps_at_4 = 0;
  Slam::MemoryUsage memory_at_4;
  for (int k = 0; k < 8 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&trimmed, k).accepted) << k;
    if (k < 4 * 160) {
      ASSERT_TRUE(BackAndForthStep(&plain, k).accepted) << k;
    }
    if (k == 4 * 160 - 1) {
      live_nodes_at_4 = trimmed.num_live_nodes();
      live_submaps_at_4 = trimmed.num_live_submaps();
      memory_at_4 = trimmed.Memory();
    }
  }
  // What SLAM holds: the grids and the live nodes' scans stay the room's, below what the
  // untrimmed graph holds after half the passes; what grows with the passes is the trimmed
  // nodes' records (and the trajectory), a small part of a live node's.
  const Slam::MemoryUsage memory = trimmed.Memory(), plain_memory = plain.Memory();
  std::printf(
      "SLAM data after 4 / 8 passes: grids %zu / %zu kB, live nodes %zu / %zu kB, trimmed "
      "nodes %zu / %zu kB; untrimmed after 4: grids %zu kB, nodes %zu kB\n",
      memory_at_4.submap_grids / 1024, memory.submap_grids / 1024, memory_at_4.live_nodes / 1024,
      memory.live_nodes / 1024, memory_at_4.trimmed_nodes / 1024, memory.trimmed_nodes / 1024,
      plain_memory.submap_grids / 1024, plain_memory.live_nodes / 1024);
  EXPECT_LT(memory.submap_grids, plain_memory.submap_grids);
  EXPECT_LT(memory.live_nodes + memory.trimmed_nodes, plain_memory.live_nodes / 2);
  EXPECT_LT(memory.submap_grids, memory_at_4.submap_grids * 3 / 2);
  EXPECT_LT(memory.live_nodes, memory_at_4.live_nodes * 3 / 2);
  EXPECT_GT(memory.trimmed_nodes, memory_at_4.trimmed_nodes);
  const double per_live = static_cast<double>(memory.live_nodes) / trimmed.num_live_nodes();
  const double per_trimmed =
      static_cast<double>(memory.trimmed_nodes) / (trimmed.num_nodes() - trimmed.num_live_nodes());
  EXPECT_LT(per_trimmed, per_live / 20) << per_trimmed << " against " << per_live << " bytes";
  EXPECT_EQ(memory.Total(), memory.submap_grids + memory.precomputations + memory.live_nodes +
                                memory.trimmed_nodes + memory.trimmed_submaps + memory.graph +
                                memory.trajectory);
  // A trimmed submap keeps its record and node list, nothing of its grid or samples.
  EXPECT_LT(memory.trimmed_submaps, trimmed.stats().submaps_trimmed * 512);
  std::printf("4 passes: %d nodes, %lld submaps untrimmed; %d nodes, %d submaps live after 4 "
              "passes, %d, %d after 8 (%lld submaps trimmed)\n",
              plain.num_nodes(), (long long)plain.stats().submaps, live_nodes_at_4,
              live_submaps_at_4, trimmed.num_live_nodes(), trimmed.num_live_submaps(),
              (long long)trimmed.stats().submaps_trimmed);
  EXPECT_EQ(plain.num_live_nodes(), plain.num_nodes());
  EXPECT_GT(plain.num_nodes(), 200);
  EXPECT_LT(live_nodes_at_4, plain.num_nodes() / 2);
  EXPECT_LE(trimmed.num_live_nodes(), live_nodes_at_4 + 20);
  EXPECT_LE(trimmed.num_live_submaps(), live_submaps_at_4 + 2);
  EXPECT_GT(trimmed.stats().submaps_trimmed, 30);
  EXPECT_EQ(trimmed.num_nodes() - trimmed.num_live_nodes(), trimmed.stats().nodes_trimmed);
  trimmed.Optimise();
  EXPECT_LT(BackAndForthError(trimmed), 0.05);
  EXPECT_LT(BackAndForthError(plain), 0.05);
  Eigen::MatrixXd cov;
  ASSERT_TRUE(trimmed.JointCovariance({trimmed.num_nodes() - 1}, &cov));
  EXPECT_GT(cov(0, 0), 0);
  // A trimmed node has no covariance; the map is drawn from the live nodes only.
  int gone = 1;
  while (!trimmed.NodeTrimmed(gone)) ++gone;
  EXPECT_FALSE(trimmed.JointCovariance({gone}, &cov));
  EXPECT_GT(trimmed.RenderMap().width, 150);  // the 10 m room at 5 cm
}

// MAP's occupancy (0-100, -1 unknown) at map-frame point (x, y).
int MapValueAt(const OccupancyMap& map, double x, double y) {
  const int cx = static_cast<int>(std::floor((x - map.origin_x_m) / map.resolution_m));
  const int cy = static_cast<int>(std::floor((y - map.origin_y_m) / map.resolution_m));
  if (cx < 0 || cy < 0 || cx >= map.width || cy >= map.height) return -1;
  return map.cells[static_cast<size_t>(cy) * map.width + cx];
}

// The largest MAP value within 0.06 m of (x, y), on a 0.02 m raster.
int MaxValueNear(const OccupancyMap& map, double x, double y) {
  int value = -1;
  for (double dx = -0.06; dx <= 0.06; dx += 0.02) {
    for (double dy = -0.06; dy <= 0.06; dy += 0.02)
      value = std::max(value, MapValueAt(map, x + dx, y + dy));
  }
  return value;
}

// How a planner reads a MAP value (config/explore.yaml's thresholds): unknown, free, between,
// occupied.
int MapClass(int value) { return value < 0 ? 0 : value <= 25 ? 1 : value < 65 ? 2 : 3; }

// The cells of `reference` (known in either map) whose value in `other`, read at the cell's
// centre, differs (`by_class`: differs in MapClass).
int CellsDiffering(const OccupancyMap& other, const OccupancyMap& reference,
                   bool by_class = false) {
  int differing = 0;
  for (int y = 0; y < reference.height; ++y) {
    for (int x = 0; x < reference.width; ++x) {
      const double mx = reference.origin_x_m + (x + 0.5) * reference.resolution_m;
      const double my = reference.origin_y_m + (y + 0.5) * reference.resolution_m;
      const int a = MapValueAt(other, mx, my);
      const int b = reference.cells[static_cast<size_t>(y) * reference.width + x];
      differing += by_class ? MapClass(a) != MapClass(b) : a != b;
    }
  }
  // Known cells of `other` outside `reference`.
  int known_other = 0, known_inside = 0;
  for (int8_t c : other.cells) known_other += c >= 0;
  for (int y = 0; y < reference.height; ++y) {
    for (int x = 0; x < reference.width; ++x) {
      known_inside += MapValueAt(other, reference.origin_x_m + (x + 0.5) * reference.resolution_m,
                                 reference.origin_y_m + (y + 0.5) * reference.resolution_m) >= 0;
    }
  }
  return differing + std::max(0, known_other - known_inside);
}

// Known cells of a map.
int KnownCells(const OccupancyMap& map) {
  int known = 0;
  for (int8_t c : map.cells) known += c >= 0;
  return known;
}

TEST(SlamTrimTest, AnObstacleSeenOnlyOnARevisitIsMapped) {
  // A pillar appears after two passes. The submaps of the pass that first sees it map nothing
  // else new, yet they stay (the same drive without the pillar trims them); later passes are
  // trimmed again. Without a budget for such submaps: the room's three submaps that hold its
  // area would allow none.
  SlamOptions o = BackAndForthOptions(true);
  o.trim.obstacle_submaps_per_area_submap = 1e9;
  Slam plain{o};
  Slam pillar{o};
  int live_after_3 = 0, plain_after_3 = 0;
  for (int k = 0; k < 5 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&plain, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&pillar, k, k >= 2 * 160).accepted);
    if (k == 3 * 160 - 1) {
      live_after_3 = pillar.num_live_submaps();
      plain_after_3 = plain.num_live_submaps();
    }
  }
  std::printf("live submaps after 3 passes: %d with the pillar, %d without; after 5: %d, %d\n",
              live_after_3, plain_after_3, pillar.num_live_submaps(), plain.num_live_submaps());
  EXPECT_GE(live_after_3, plain_after_3 + 2);
  EXPECT_LE(pillar.num_live_submaps() - live_after_3, plain.num_live_submaps() - plain_after_3 + 1);
}

TEST(SlamTrimTest, TheBudgetCapsTheSubmapsKeptForNewObstacles) {
  // The pillar drive with 0.5 submaps kept for new obstacles per submap that holds area: the
  // room's three allow one (1 <= 1.5); the pass that first sees the pillar would keep more
  // without the cap, so the rest are trimmed with their new obstacles.
  SlamOptions o = BackAndForthOptions(true);
  o.trim.obstacle_submaps_per_area_submap = 0.5;
  Slam plain{o};
  Slam pillar{o};
  for (int k = 0; k < 5 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&plain, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&pillar, k, k >= 2 * 160).accepted);
  }
  std::printf(
      "kept for new obstacles %lld, trimmed over the budget %lld, live submaps %d (%d "
      "without the pillar)\n",
      (long long)pillar.stats().submaps_kept_new_obstacles,
      (long long)pillar.stats().submaps_trimmed_over_obstacle_budget, pillar.num_live_submaps(),
      plain.num_live_submaps());
  EXPECT_EQ(pillar.stats().submaps_kept_new_area, 0);
  EXPECT_EQ(pillar.stats().submaps_kept_new_obstacles, 1);
  EXPECT_GT(pillar.stats().submaps_trimmed_over_obstacle_budget, 0);
  EXPECT_EQ(pillar.num_live_submaps(), plain.num_live_submaps() + 1);
}

TEST(SlamTrimTest, PastTheBudgetANewObstacleStaysOnMapWithoutItsSubmaps) {
  // The pillar of the test above, with no budget for submaps kept for new obstacles: the
  // passes that see it are trimmed as in the same drive without the pillar, so the live graph
  // stays the room's. The freed nodes' returns on the pillar keep it on MAP, where a planner
  // reads it as occupied (MapClass 3) from the pass after it appeared on, and after a reload,
  // which keeps the counts the budget is made of.
  SlamOptions o = BackAndForthOptions(true);
  o.trim.obstacle_submaps_per_area_submap = 0;
  Slam plain{o};
  Slam pillar{o};
  int pillar_at_3 = -1;
  for (int k = 0; k < 5 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&plain, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&pillar, k, k >= 2 * 160).accepted);
    // The map frame is the first scan's pose, (-3, 0): the pillar's face towards the drive is
    // at y = 1.3 from x = 1.8 to 2.2.
    if (k == 3 * 160 - 1) pillar_at_3 = MaxValueNear(pillar.RenderMap(), 2.0, 1.3);
  }
  const OccupancyMap map = pillar.RenderMap();
  const int pillar_at_5 = MaxValueNear(map, 2.0, 1.3);
  const int before_pillar = MaxValueNear(map, 2.0, 0.9);
  std::printf(
      "live submaps after 5 passes: %d with the pillar, %d without; MAP at its face after 3 / 5 "
      "passes %d / %d, in front of it %d\n",
      pillar.num_live_submaps(), plain.num_live_submaps(), pillar_at_3, pillar_at_5, before_pillar);
  EXPECT_LE(pillar.num_live_submaps(), plain.num_live_submaps() + 1);
  EXPECT_GT(pillar.stats().submaps_trimmed, 20);
  EXPECT_EQ(pillar.stats().submaps_kept_new_obstacles, 0);
  EXPECT_GT(pillar.stats().submaps_trimmed_over_obstacle_budget, 0);
  EXPECT_EQ(MapClass(pillar_at_3), 3);
  EXPECT_EQ(MapClass(pillar_at_5), 3);
  EXPECT_EQ(MapClass(before_pillar), 1);
  // Without the pillar the same place is free.
  EXPECT_EQ(MapClass(MaxValueNear(plain.RenderMap(), 2.0, 1.3)), 1);
  const std::string path = ::testing::TempDir() + "/slam_state_pillar.pg";
  pillar.Save(path);
  Slam resumed{o};
  resumed.Load(path);
  EXPECT_EQ(resumed.RenderMap().cells, map.cells);
  EXPECT_EQ(resumed.stats().submaps_kept_new_area, pillar.stats().submaps_kept_new_area);
  EXPECT_EQ(resumed.stats().submaps_kept_new_obstacles, 0);
}

TEST(SlamTrimTest, ASmallObstacleSeenOnlyOnARevisitStaysOnMapAfterItsSubmapsAreTrimmed) {
  // A 0.08 m post at (-0.9, 1.5) appears after two passes, seen only from the far end of the
  // drive (x < -2.5). It lies in one cell of the trim raster (0.04 m^2, less new obstacle than
  // min_new_obstacle_m2), so the submaps that see it are trimmed. The nodes freed with them keep
  // their returns on it: MAP still calls it more likely occupied than free, against the two
  // passes that saw its place free (31 when the freed nodes keep nothing).
  Slam slam{BackAndForthOptions(true)};
  Pillar post;
  post.x_m = -0.9;
  post.half_m = 0.04;
  post.seen_below_x = -2.5;
  const int passes = 5;
  for (int k = 0; k < passes * 160; ++k) {
    post.present = k >= 2 * 160;
    ASSERT_TRUE(BackAndForthStep(&slam, k, post).accepted);
  }
  int trimmed_nodes = 0;
  for (int n = 0; n < slam.num_nodes(); ++n) trimmed_nodes += slam.NodeTrimmed(n);
  const OccupancyMap map = slam.RenderMap();
  // The map frame is the first scan's pose, (-3, 0): the post is at (2.1, 1.5).
  const int at_post = MaxValueNear(map, 2.1, 1.5);
  // Composed from the submaps, the returns the freed nodes keep are drawn on one parity's
  // evidence that the place was free (the two passes before the post), and the post stays below
  // even; the rest of the room reads as drawn from the nodes.
  const OccupancyMap composed = slam.ComposeMap();
  const int composed_at_post = MaxValueNear(composed, 2.1, 1.5);
  std::printf(
      "%d of %d nodes trimmed, MAP at the post %d (composed from submaps %d; %d of %d "
      "known cells read otherwise by a planner)\n",
      trimmed_nodes, slam.num_nodes(), at_post, composed_at_post,
      CellsDiffering(composed, map, true), KnownCells(map));
  EXPECT_GT(slam.stats().nodes_trimmed, slam.num_nodes() / 2);
  EXPECT_GT(at_post, 50);
  EXPECT_GT(composed_at_post, 35);
  EXPECT_LT(CellsDiffering(composed, map, true), KnownCells(map) / 40);
  // What the freed nodes keep is in the state file.
  const std::string path = ::testing::TempDir() + "/slam_state_post.pg";
  slam.Save(path);
  Slam resumed{BackAndForthOptions(true)};
  resumed.Load(path);
  const OccupancyMap reloaded = resumed.RenderMap();
  EXPECT_EQ(reloaded.cells, map.cells);
}

TEST(SlamTrimTest, APlaceOnlyTrimmedSubmapsSawIsNotNewToALaterPass) {
  // Windows 0.4 m wide in the wall y = 3 open onto space beyond the scanner's reach (free-space
  // rays of 4.5 m). With min_fresh_area_m2 at 2 m^2, a submap that sees through one window maps
  // less new area than that (14-43 raster cells of 0.04 m^2 here) and is trimmed; through two,
  // more (62-66 cells when the first window's cells count as new). Pass 2 opens the window at
  // x = -1; passes 4-6 open it and one at x = 0.6. The area the trimmed submaps of pass 2 saw
  // still counts as known, so pass 4 keeps no submap for its area; a Slam resumed from the state
  // file written after pass 4 maps nothing new in passes 5-6 even when a tenth of the area would
  // keep a submap. The reference drive, with only the second window in pass 4, ends pass 4 with as
  // many live submaps.
  SlamOptions o = BackAndForthOptions(true);
  o.scan.missing_data_ray_length_m = 4.5;
  o.trim.min_new_obstacle_m2 = 1e9;  // judged by area alone
  o.trim.min_fresh_area_m2 = 2.0;
  Slam slam{o}, reference{o};
  auto windows = [](int pass, bool reference) {
    Pillar room;
    if (pass == 2 && !reference) room.windows_x = {-1.0};
    if (pass >= 4)
      room.windows_x = reference ? std::vector<double>{0.6} : std::vector<double>{-1.0, 0.6};
    return room;
  };
  int k = 0;
  for (; k < 5 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k, windows(k / 160, false)).accepted) << k;
    ASSERT_TRUE(BackAndForthStep(&reference, k, windows(k / 160, true)).accepted) << k;
  }
  std::printf(
      "after 4 passes: %lld submaps kept for their area (reference %lld), %lld trimmed, "
      "%d live (reference %d)\n",
      (long long)slam.stats().submaps_kept_new_area,
      (long long)reference.stats().submaps_kept_new_area, (long long)slam.stats().submaps_trimmed,
      slam.num_live_submaps(), reference.num_live_submaps());
  EXPECT_GT(slam.stats().submaps_trimmed, 25);
  EXPECT_EQ(slam.stats().submaps_kept_new_area, 0);
  EXPECT_EQ(slam.num_live_submaps(), reference.num_live_submaps());
  // The known cells go through the state file.
  const std::string path = ::testing::TempDir() + "/slam_state_windows.pg";
  slam.Save(path);
  // Resumed with a tenth of the area: a submap whose window cells counted as new would stay.
  SlamOptions strict = o;
  strict.trim.min_fresh_area_m2 = 0.2;
  Slam resumed{strict};
  resumed.Load(path);
  for (; k < 7 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&resumed, k, windows(k / 160, false)).accepted) << k;
  }
  std::printf("resumed, passes 5-6: %lld submaps kept for their area, %lld trimmed, %d live\n",
              (long long)resumed.stats().submaps_kept_new_area,
              (long long)resumed.stats().submaps_trimmed, resumed.num_live_submaps());
  EXPECT_GE(resumed.stats().submaps_trimmed, slam.stats().submaps_trimmed + 10);
  EXPECT_EQ(resumed.stats().submaps_kept_new_area, 0);
  EXPECT_EQ(resumed.num_live_submaps(), slam.num_live_submaps());
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A state file's graph: the body without the sealing line and the local state after the
// constraints (140 bytes with the trailer), which a load resets to resume.
std::string GraphPart(const std::string& path) {
  const std::string file = ReadBytes(path);
  const std::string body = file.substr(file.find('\n') + 1);
  return body.substr(0, body.size() - 140);
}

TEST(SlamTrimTest, KeptNodesSurviveAndTheTrimmedGraphResumesFromItsStateFile) {
  Slam slam{BackAndForthOptions(true)};
  int k = 0;
  for (; k < 160; ++k) ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
  const int kept = slam.num_nodes() - 30;  // a node of a finished submap, held for a client
  // Held once, unknown ids left out; the latest node first.
  EXPECT_EQ(slam.HoldAnchors({kept, kept, -1, 1000000}),
            (std::vector<int>{slam.num_nodes() - 1, kept}));
  const Rigid2d kept_pose = slam.NodePose(kept);
  for (; k < 4 * 160; ++k) ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
  ASSERT_GT(slam.stats().nodes_trimmed, 0);
  EXPECT_FALSE(slam.NodeTrimmed(kept));
  EXPECT_NEAR((slam.NodePose(kept).translation() - kept_pose.translation()).norm(), 0, 0.05);
  Eigen::MatrixXd cov;
  EXPECT_TRUE(slam.JointCovariance({slam.num_nodes() - 1, kept}, &cov));

  const std::string path = ::testing::TempDir() + "/slam_state_trimmed.pg";
  slam.Save(path);
  Slam resumed{BackAndForthOptions(true)};
  resumed.Load(path);
  EXPECT_EQ(resumed.num_live_nodes(), slam.num_live_nodes());
  EXPECT_EQ(resumed.num_live_submaps(), slam.num_live_submaps());
  EXPECT_EQ(resumed.stats().nodes_trimmed, slam.stats().nodes_trimmed);
  // The stored forms (finished grids' codes, packed returns, trimmed nodes' poses alone) load
  // as they were: the graph saved again is the same, byte for byte.
  const std::string again = ::testing::TempDir() + "/slam_state_trimmed_again.pg";
  resumed.Save(again);
  EXPECT_TRUE(GraphPart(again) == GraphPart(path));
  // Both continue the drive the same way (the resumed one from its file).
  for (; k < 5 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&resumed, k).accepted);
  }
  EXPECT_NEAR((resumed.CurrentPose().translation() - slam.CurrentPose().translation()).norm(), 0,
              0.05);
  const double phase = std::fmod(0.05 * (k - 1), 8.0);
  EXPECT_NEAR(resumed.CurrentPose().translation().x(), phase < 4.0 ? phase : 8.0 - phase, 0.05);
}

TEST(SlamTrimTest, ANodeAClientKeepsOutlivesItsSubmapsAndGoesOnceReleased) {
  // In the third pass every submap maps nothing new. A node of that pass is kept while its
  // submaps finish: they are trimmed all the same (the live graph is that of the same drive
  // without a client), and the node stays, following the graph with a computable covariance.
  // Released, it goes at the next request and the graph stays one piece.
  Slam slam{BackAndForthOptions(true)};
  Slam unkept{BackAndForthOptions(true)};
  int k = 0;
  for (; k < 2 * 160 + 40; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&unkept, k).accepted);
  }
  const int kept = slam.num_nodes() - 1;
  slam.HoldAnchors({kept});
  for (; k < 3 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&unkept, k).accepted);
  }
  std::printf("kept node %d: %d nodes kept alone, %d live submaps (%d without the client)\n", kept,
              slam.num_nodes_kept_for_anchors(), slam.num_live_submaps(),
              unkept.num_live_submaps());
  ASSERT_TRUE(unkept.NodeTrimmed(kept));  // without the client it goes with its submaps
  EXPECT_EQ(slam.num_live_submaps(), unkept.num_live_submaps());
  EXPECT_EQ(slam.num_live_nodes(), unkept.num_live_nodes() + 1);
  EXPECT_EQ(slam.num_nodes_kept_for_anchors(), 1);
  EXPECT_FALSE(slam.NodeTrimmed(kept));
  // Its pose is the drive's truth at its step (x from -3 to 1 m and back; map frame at x = -3).
  const double phase = std::fmod(0.05 * (2 * 160 + 39), 8.0);
  EXPECT_NEAR(slam.NodePose(kept).translation().x(), phase < 4.0 ? phase : 8.0 - phase, 0.05);
  EXPECT_NEAR(slam.NodePose(kept).translation().y(), 0, 0.05);
  Eigen::MatrixXd cov;
  ASSERT_TRUE(slam.JointCovariance({slam.num_nodes() - 1, kept}, &cov));
  EXPECT_GT(cov(3, 3), 0);
  EXPECT_LT(std::sqrt(cov(3, 3)), 1.0);
  // Still requested: still kept, also through a save and load.
  slam.HoldAnchors({kept});
  EXPECT_FALSE(slam.NodeTrimmed(kept));
  const std::string path = ::testing::TempDir() + "/slam_state_kept_node.pg";
  slam.Save(path);
  Slam resumed{BackAndForthOptions(true)};
  resumed.Load(path);
  EXPECT_EQ(resumed.num_nodes_kept_for_anchors(), 1);
  EXPECT_FALSE(resumed.NodeTrimmed(kept));
  // Released.
  for (Slam* s : {&slam, &resumed}) {
    EXPECT_EQ(s->HoldAnchors({}), (std::vector<int>{s->num_nodes() - 1}));
    EXPECT_EQ(s->num_nodes_kept_for_anchors(), 0);
    EXPECT_TRUE(s->NodeTrimmed(kept));
    EXPECT_EQ(s->num_live_nodes(), unkept.num_live_nodes());
    EXPECT_EQ(s->num_nodes() - s->num_live_nodes(), s->stats().nodes_trimmed);
    // The latest node's covariance is computable and the drive goes on on the truth.
    EXPECT_TRUE(s->JointCovariance({s->num_nodes() - 1}, &cov));
  }
  for (; k < 4 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&resumed, k).accepted);
  }
  for (Slam* s : {&slam, &resumed}) {
    s->Optimise();
    EXPECT_LT(BackAndForthError(*s), 0.05);
  }
}

// The drive of AnOptimisationSaysWhetherItHadNewLoopClosures with loop closures weighted per
// direction by their match: loops still close, and each closure's shape survives a save and a load
// (the graph saved again is the same, byte for byte).
TEST(SlamStateFileTest, LoopClosureShapesAreKeptThroughASaveAndALoad) {
  SlamOptions o;
  o.local.scans_per_submap = 10;
  o.local.node_max_distance_m = 0.1;
  o.graph.optimise_every_n_nodes = 10;
  o.loop.sampling_ratio = 1.0;
  o.loop.weight_by_match_information = true;
  Slam slam{o};
  for (int k = 0; k < 200; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
  }
  EXPECT_GT(slam.stats().loop_closures, 0);
  const std::string path = ::testing::TempDir() + "/slam_state_shapes.pg";
  const auto graph_part = [&] { return GraphPart(path); };
  slam.Save(path);
  const std::string saved = graph_part();
  Slam loaded{o};
  loaded.Load(path);
  loaded.Save(path);
  // A shape dropped on loading (read as the identity) would change the re-saved graph.
  EXPECT_GT(saved.size(), 1000u);
  EXPECT_TRUE(graph_part() == saved);
}

TEST(SlamStateFileTest, FlippedNanAndOtherVersionFilesAreRefusedAndLeaveTheSlamClean) {
  Slam first{SlamOptions()};
  for (int k = 0; k <= 10; ++k) {
    first.AddOdometry(0.1 * k, Rigid2d(0.05 * k, 0, 0));
    ASSERT_TRUE(first.AddScan(MakeScan(0.1 * k)).accepted);
  }
  const std::string path = ::testing::TempDir() + "/slam_state_refused.pg";
  first.Save(path);
  const std::string file = ReadBytes(path);
  ASSERT_EQ(file.rfind("# sarmap-state slam-pose-graph v2 ", 0), 0u) << file.substr(0, 60);
  const std::string body = file.substr(file.find('\n') + 1);
  const auto refused = [&](const std::string& why) {
    Slam slam{SlamOptions()};
    try {
      slam.Load(path);
      ADD_FAILURE() << "loaded: " << why;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    // Nothing of the refused file was taken: a clean start maps from scratch.
    EXPECT_EQ(slam.num_nodes(), 0);
    slam.AddOdometry(5.0, Rigid2d(0, 0, 0));
    EXPECT_TRUE(slam.AddScan(MakeScan(5.0)).accepted);
    EXPECT_NEAR(slam.CurrentPose().translation().norm(), 0, 1e-9);
  };
  // One bit flipped in the middle of the graph.
  std::string flipped = file;
  flipped[file.size() / 2] ^= 0x10;
  std::ofstream(path, std::ios::binary | std::ios::trunc) << flipped;
  refused("checksum");
  // A NaN saved by the node itself (sealed, checksum correct): last_node_time, 48 bytes before
  // the end (trailer 8, odom segment 4, unused beam count 4, last node pose 24).
  std::string with_nan = body;
  const double nan = std::nan("");
  with_nan.replace(with_nan.size() - 48, sizeof(double), reinterpret_cast<const char*>(&nan),
                   sizeof(double));
  common::WriteSealedState(path, "slam-pose-graph", 2, with_nan);
  refused("non-finite");
  common::WriteSealedState(path, "slam-pose-graph", 7, body);
  refused("version 7");
  // A file written before sealing (the bare body) is still read.
  std::ofstream(path, std::ios::binary | std::ios::trunc) << body;
  Slam legacy{SlamOptions()};
  legacy.Load(path);
  EXPECT_EQ(legacy.num_nodes(), first.num_nodes());
}

LaserScan ToLaserScan(const CarmenLaser& l) {
  LaserScan s;
  s.time_s = l.time_s;
  s.angle_min_rad = l.angle_min_rad;
  s.angle_increment_rad = l.angle_increment_rad;
  s.range_min_m = 0;
  s.range_max_m = std::nextafter(static_cast<float>(l.range_max_m), 0.f);
  s.ranges_m = l.ranges_m;
  return s;
}

// Feeds the Intel log in line (recording) order, as sarmap-slam-offline does with CARMEN logs,
// scans [first_scan, max_scans) and the odometry between them; with `interlace`, scan k cut to
// interlacing phase k % 4 (InterlacedLaser).
int FeedIntel(Slam* slam, int first_scan, int max_scans, bool interlace = false) {
  struct Item {
    double t;
    bool is_scan;
    CarmenOdometry odom;
    CarmenLaser laser;
  };
  static std::vector<Item> items;  // parsed once per test binary
  if (items.empty()) {
    CarmenReader reader;
    int scans = 0;
    reader.on_odometry = [&](const CarmenOdometry& o) {
      items.push_back({o.time_s, false, o, {}});
    };
    reader.on_laser = [&](const CarmenLaser& l) {
      if (scans++ > 2000) return;
      items.push_back({l.time_s, true, {}, l});
    };
    ReadCarmenFile(kIntel, &reader);
  }
  int scans = 0, fed = 0;
  for (const Item& it : items) {
    if (scans >= max_scans) break;
    if (scans >= first_scan) {
      if (it.is_scan) {
        slam->AddScan(ToLaserScan(interlace ? InterlacedLaser(it.laser, scans) : it.laser));
        ++fed;
      } else {
        slam->AddOdometry(it.t, Rigid2d(it.odom.x_m, it.odom.y_m, it.odom.theta_rad));
      }
    }
    scans += it.is_scan;
  }
  return fed;
}

constexpr int kPrefixScans = 500;  // ~100 s of the Intel log

TEST(SlamRealDataTest, IntelPrefixMatchesTheRelations) {
  if (!std::ifstream(kIntel)) GTEST_SKIP() << "shared data missing: " << kIntel;
  Slam slam{SlamOptions()};
  ASSERT_EQ(FeedIntel(&slam, 0, kPrefixScans), kPrefixScans);
  slam.Optimise();
  const auto traj = slam.Trajectory();
  ASSERT_EQ(static_cast<int>(traj.size()), kPrefixScans);
  // Relations within the prefix.
  std::vector<Relation> rel;
  for (const Relation& r : LoadRelations(kIntelRelations)) {
    if (r.t1_s >= traj.front().time_s && r.t2_s <= traj.back().time_s &&
        r.t1_s <= traj.back().time_s && r.t2_s >= traj.front().time_s) {
      rel.push_back(r);
    }
  }
  const RelationErrors e = EvaluateRelations(traj, rel);
  std::printf(
      "Intel prefix: %d relations, abs trans %.4f +- %.4f m, abs rot %.3f +- %.3f deg, "
      "%lld loop closures\n",
      e.used, e.abs_trans_m.mean, e.abs_trans_m.std, e.abs_rot_deg.mean, e.abs_rot_deg.std,
      (long long)slam.stats().loop_closures);
  EXPECT_GT(e.used, 30);
  EXPECT_EQ(e.missing, 0);
  // Regression bounds (measured values are printed above and in the README).
  EXPECT_LT(e.abs_trans_m.mean, REL_TRANS_BOUND);
  EXPECT_LT(e.abs_rot_deg.mean, REL_ROT_BOUND);
}

// Relations error of a trajectory over the relations that lie within it.
RelationErrors PrefixRelationErrors(const std::vector<StampedPose2>& traj) {
  std::vector<Relation> rel;
  for (const Relation& r : LoadRelations(kIntelRelations)) {
    if (r.t1_s >= traj.front().time_s && r.t2_s <= traj.back().time_s &&
        r.t1_s <= traj.back().time_s && r.t2_s >= traj.front().time_s) {
      rel.push_back(r);
    }
  }
  return EvaluateRelations(traj, rel);
}

constexpr int kInterlacedScans = 1000;  // ~200 s of the Intel log, with loops

TEST(SlamRealDataTest, IntelInterlacedUsesEveryScanClosesLoopsAndMatchesThePlainLog) {
  if (!std::ifstream(kIntel)) GTEST_SKIP() << "shared data missing: " << kIntel;
  // The Intel scans re-cut into four interlaced sweeps (180 beams from -90 deg, 179 from -89,
  // 90 from -90 every 2 deg, 90 from -89 every 2 deg), the way sarmap-log-interlace-carmen
  // writes a log: every scan is used, loops are closed, the error stays near the plain log's.
  Slam plain{SlamOptions()}, interlaced{SlamOptions()};
  ASSERT_EQ(FeedIntel(&plain, 0, kInterlacedScans), kInterlacedScans);
  ASSERT_EQ(FeedIntel(&interlaced, 0, kInterlacedScans, true), kInterlacedScans);
  plain.Optimise();
  interlaced.Optimise();
  const RelationErrors p = PrefixRelationErrors(plain.Trajectory());
  const RelationErrors i = PrefixRelationErrors(interlaced.Trajectory());
  std::printf(
      "Intel first %d scans: plain %.4f m, %.3f deg, %lld loop closures; interlaced %.4f m, "
      "%.3f deg, %lld loop closures, %lld of %d scans used\n",
      kInterlacedScans, p.abs_trans_m.mean, p.abs_rot_deg.mean,
      (long long)plain.stats().loop_closures, i.abs_trans_m.mean, i.abs_rot_deg.mean,
      (long long)interlaced.stats().loop_closures,
      (long long)(interlaced.stats().scans - interlaced.stats().rejected_scans), kInterlacedScans);
  EXPECT_EQ(interlaced.stats().rejected_scans, 0);
  EXPECT_EQ(static_cast<int>(interlaced.Trajectory().size()), kInterlacedScans);
  EXPECT_GT(interlaced.stats().loop_closures, plain.stats().loop_closures / 2);
  EXPECT_EQ(i.used, p.used);
  EXPECT_GT(i.used, 50);
  EXPECT_LT(i.abs_trans_m.mean, 1.3 * p.abs_trans_m.mean + 0.005);
  EXPECT_LT(i.abs_rot_deg.mean, 1.3 * p.abs_rot_deg.mean + 0.05);
}

TEST(SlamRealDataTest, SaveLoadResumesMapping) {
  if (!std::ifstream(kIntel)) GTEST_SKIP() << "shared data missing: " << kIntel;
  const int half = kPrefixScans / 2;
  Slam first{SlamOptions()};
  FeedIntel(&first, 0, half);
  const std::string path = ::testing::TempDir() + "/slam_resume.pg";
  first.Save(path);
  // A new process loads the saved state and continues with the rest of the log.
  Slam resumed{SlamOptions()};
  resumed.Load(path);
  EXPECT_EQ(resumed.num_nodes(), first.num_nodes());
  FeedIntel(&resumed, half, kPrefixScans);
  resumed.Optimise();
  EXPECT_GT(resumed.num_nodes(), first.num_nodes());
  // The resumed map continues the first one: its poses agree with an uninterrupted run.
  Slam full{SlamOptions()};
  FeedIntel(&full, 0, kPrefixScans);
  full.Optimise();
  const Rigid2d a = resumed.CurrentPose(), b = full.CurrentPose();
  std::printf("resumed end pose %.3f %.3f %.3f, uninterrupted %.3f %.3f %.3f\n",
              a.translation().x(), a.translation().y(), a.yaw_rad(), b.translation().x(),
              b.translation().y(), b.yaw_rad());
  EXPECT_LT((a.translation() - b.translation()).norm(), 0.3);
  EXPECT_LT(std::abs(std::remainder(a.yaw_rad() - b.yaw_rad(), 2 * M_PI)), 0.05);
  // A truncated file is refused with a clear error.
  {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream out(path + ".cut", std::ios::binary);
    out.write(bytes.data(), bytes.size() / 2);
  }
  Slam broken{SlamOptions()};
  EXPECT_THROW(broken.Load(path + ".cut"), std::runtime_error);
  // Localisation only on the saved map: scans of the mapped stretch, replayed, are tracked
  // against the map (no new nodes) and land where mapping put them.
  Slam localiser{SlamOptions()};
  localiser.SetLocalisationOnly(true);
  localiser.Load(path);
  const int nodes_before = localiser.num_nodes();
  {
    // Start from the mapped pose of the first replayed scan, perturbed by 0.14 m and 3 deg.
    Slam probe{SlamOptions()};
    FeedIntel(&probe, 0, half - 150 + 1);
    const Rigid2d start = probe.CurrentPose();
    localiser.SetLocalisationStart(
        Rigid2d(start.translation() + Eigen::Vector2d(0.1, -0.1), start.yaw_rad() + 0.05));
  }
  FeedIntel(&localiser, half - 150, half);
  EXPECT_EQ(localiser.num_nodes(), nodes_before);
  const auto traj = localiser.Trajectory();
  ASSERT_EQ(traj.size(), 150u);
  const auto first_traj = first.Trajectory();
  std::vector<double> dev;
  for (const auto& p : traj) {
    StampedPose2 q;
    ASSERT_TRUE(PoseAt(first_traj, p.time_s, 1e-3, 0.5, &q));
    dev.push_back(std::hypot(p.x_m - q.x_m, p.y_m - q.y_m));
  }
  std::sort(dev.begin(), dev.end());
  std::printf("localisation-only: median deviation from the mapping run %.3f m, 90%% %.3f m\n",
              dev[dev.size() / 2], dev[dev.size() * 9 / 10]);
  // Measured: the localiser tracks the map but keeps most of the 0.14 m start offset (median
  // ~0.13 m, 90% ~0.33 m): a known weakness, asserted as measured rather than hidden.
  EXPECT_LT(dev[dev.size() / 2], 0.2);
  EXPECT_LT(dev[dev.size() * 9 / 10], 0.4);
  const auto full_traj = full.Trajectory();
  // Map export: PGM + YAML that read back.
  const OccupancyMap map = full.RenderMap();
  SaveMapServerMap(map, ::testing::TempDir() + "/intel_prefix");
  const OccupancyMap back = LoadMapServerMap(::testing::TempDir() + "/intel_prefix.yaml");
  EXPECT_EQ(back.width, map.width);
  EXPECT_EQ(back.height, map.height);
  EXPECT_NEAR(back.origin_x_m, map.origin_x_m, 1e-6);
  int occupied_agree = 0, occupied = 0;
  for (size_t i = 0; i < map.cells.size(); ++i) {
    if (map.cells[i] >= 65) {
      ++occupied;
      occupied_agree += back.cells[i] == 100;
    }
  }
  EXPECT_GT(occupied, 100);
  EXPECT_EQ(occupied_agree, occupied);
}

TEST(SlamRealDataTest, ResumeBridgesTheMotionMadeWhileDownWithOdometry) {
  if (!std::ifstream(kIntel)) GTEST_SKIP() << "shared data missing: " << kIntel;
  // The process dies and comes back 25 scans (~5 s, a state-save period, about a metre of driving)
  // later: the scans in between are lost, the odometry frame is the same.
  const int half = kPrefixScans / 2, gap = 25;
  Slam first{SlamOptions()};
  FeedIntel(&first, 0, half);
  const std::string path = ::testing::TempDir() + "/slam_resume_gap.pg";
  first.Save(path);
  Slam resumed{SlamOptions()};
  resumed.Load(path);
  FeedIntel(&resumed, half + gap, kPrefixScans);
  resumed.Optimise();
  Slam full{SlamOptions()};
  FeedIntel(&full, 0, kPrefixScans);
  full.Optimise();
  const Rigid2d a = resumed.CurrentPose(), b = full.CurrentPose();
  std::printf("resumed after a gap: end pose %.3f %.3f, uninterrupted %.3f %.3f\n",
              a.translation().x(), a.translation().y(), b.translation().x(), b.translation().y());
  EXPECT_LT((a.translation() - b.translation()).norm(), 0.3);
  EXPECT_LT(std::abs(std::remainder(a.yaw_rad() - b.yaw_rad(), 2 * M_PI)), 0.05);
}

TEST(SlamMapDrawingTest, KeptDrawingEqualsTheFullRenderingWhileNothingMoves) {
  // No optimisation runs: no drawn node moves, so the drawing is only ever extended and equals
  // the rendering from scratch after every call.
  SlamOptions o = BackAndForthOptions(false);
  o.scan.map_source = "nodes";
  o.graph.optimise_every_n_nodes = 0;
  Slam slam{o};
  int calls = 0, nodes_at_last_call = 0;
  for (int k = 0; k < 2 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
    if (k % 25 != 24) continue;
    ++calls;
    nodes_at_last_call = slam.num_nodes();
    const OccupancyMap drawn = slam.DrawMap();
    ASSERT_GT(drawn.width, 0);
    EXPECT_EQ(CellsDiffering(drawn, slam.RenderMap()), 0) << "after scan " << k;
  }
  EXPECT_EQ(slam.map_drawing_stats().redraws, 1);
  EXPECT_EQ(slam.map_drawing_stats().draws, calls);
  EXPECT_EQ(slam.map_drawing_stats().nodes_drawn, nodes_at_last_call);
}

TEST(SlamMapDrawingTest, AnOptimisationThatMovesDrawnScansRedraws) {
  // With no shift tolerated, every optimisation that moves a drawn node forces a redraw, so the
  // drawing equals the rendering from scratch after every call; with the default half cell the
  // drawing is redrawn less often, and a planner reads it as the rendering from scratch in all
  // but a few cells (cells on a wall's edge, where a return moved to the neighbour cell).
  SlamOptions exact = BackAndForthOptions(false);
  exact.scan.map_source = "nodes";
  exact.scan.map_redraw_shift_cells = 0;
  SlamOptions tolerant = exact;
  tolerant.scan.map_redraw_shift_cells = 0.5;
  Slam a{exact}, b{tolerant};
  int calls = 0, worst_differing = 0, worst_class_differing = 0, known = 0;
  for (int k = 0; k < 3 * 160; ++k) {
    ASSERT_TRUE(BackAndForthStep(&a, k).accepted);
    ASSERT_TRUE(BackAndForthStep(&b, k).accepted);
    if (k % 25 != 24) continue;
    ++calls;
    const OccupancyMap full = a.RenderMap();
    EXPECT_EQ(CellsDiffering(a.DrawMap(), full), 0) << "after scan " << k;
    const OccupancyMap kept = b.DrawMap();
    worst_differing = std::max(worst_differing, CellsDiffering(kept, full));
    worst_class_differing = std::max(worst_class_differing, CellsDiffering(kept, full, true));
    known = 0;
    for (int8_t c : full.cells) known += c >= 0;
  }
  std::printf(
      "%d MAP calls: %lld / %lld redraws (no shift / half a cell tolerated); the kept "
      "drawing differs from the full rendering in at most %d of %d known cells, %d read "
      "otherwise by a planner\n",
      calls, (long long)a.map_drawing_stats().redraws, (long long)b.map_drawing_stats().redraws,
      worst_differing, known, worst_class_differing);
  EXPECT_GT(a.stats().optimisations, 10);
  EXPECT_GT(a.map_drawing_stats().redraws, 1);
  EXPECT_LE(b.map_drawing_stats().redraws, a.map_drawing_stats().redraws);
  EXPECT_LT(worst_class_differing, known / 50);
}

TEST(SlamMapDrawingTest, ALoadedGraphIsDrawnAfresh) {
  SlamOptions o = BackAndForthOptions(true);
  o.scan.map_source = "nodes";
  Slam slam{o};
  for (int k = 0; k < 2 * 160; ++k) ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
  const std::string path = ::testing::TempDir() + "/slam_state_drawing.pg";
  slam.Save(path);
  Slam other{o};
  for (int k = 0; k < 40; ++k) ASSERT_TRUE(BackAndForthStep(&other, k).accepted);
  ASSERT_GT(other.DrawMap().width, 0);
  other.Load(path);
  EXPECT_EQ(CellsDiffering(other.DrawMap(), slam.RenderMap()), 0);
  EXPECT_EQ(other.map_drawing_stats().redraws, 2);
}

TEST(SlamMapDrawingTest, MapComposedFromSubmapsReadsAsTheMapDrawnFromNodes) {
  // One pass and back along the room: every node is in two live submaps, and the composed map
  // has the nodes' evidence; a planner reads it as the map drawn from every node in all but the
  // cells where one submap's rounding differs from the other's (wall edges).
  SlamOptions o = BackAndForthOptions(false);
  o.scan.map_source = "submaps";
  Slam slam{o};
  for (int k = 0; k < 2 * 160; ++k) ASSERT_TRUE(BackAndForthStep(&slam, k).accepted);
  const OccupancyMap drawn = slam.RenderMap(), composed = slam.ComposeMap();
  const int known = KnownCells(drawn);
  const int by_class = CellsDiffering(composed, drawn, true);
  std::printf(
      "composed from %d submaps: %d known cells (drawn from %d nodes: %d), %d read "
      "otherwise by a planner\n",
      slam.num_live_submaps(), KnownCells(composed), slam.num_nodes(), known, by_class);
  EXPECT_GT(known, 10000);
  EXPECT_NEAR(KnownCells(composed), known, known / 50);
  EXPECT_LT(by_class, known / 50);
  // DrawMap publishes the composition (map_source submaps).
  EXPECT_EQ(CellsDiffering(slam.DrawMap(), composed), 0);
  EXPECT_EQ(slam.map_drawing_stats().draws, 1);
  EXPECT_EQ(slam.map_drawing_stats().redraws, 0);
}

TEST(SlamMapDrawingTest, IntelMapComposedFromSubmapsReadsAsTheMapDrawnFromNodes) {
  if (!std::ifstream(kIntel)) GTEST_SKIP() << "shared data missing: " << kIntel;
  Slam slam{SlamOptions()};
  FeedIntel(&slam, 0, kPrefixScans);
  slam.Optimise();
  const OccupancyMap drawn = slam.RenderMap(), composed = slam.ComposeMap();
  const int known = KnownCells(drawn);
  const int by_class = CellsDiffering(composed, drawn, true);
  std::printf(
      "Intel, %d scans: composed from %d submaps, %d known cells (drawn from %d nodes: "
      "%d), %d read otherwise by a planner\n",
      kPrefixScans, slam.num_live_submaps(), KnownCells(composed), slam.num_nodes(), known,
      by_class);
  // 197 nodes in 3 submaps: most of the map is the first submap's first half, which only the
  // even parity holds.
  EXPECT_NEAR(KnownCells(composed), known, known / 20);
  EXPECT_LT(by_class, known / 15);
}

TEST(SlamMapDrawingTest, MapFreeFromNeedsTheMapFromNodes) {
  SlamOptions o;
  o.scan.map_free_from_m = 1.2;
  o.scan.map_source = "submaps";
  EXPECT_THROW(common::ValidateOptions(o), std::exception);
  o.scan.map_source = "nodes";
  EXPECT_NO_THROW(common::ValidateOptions(o));
}

}  // namespace
}  // namespace slam
}  // namespace sarmap
