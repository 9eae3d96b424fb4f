// The log tools end to end: sarmap-log-import-carmen writes an LCM log that decodes to the
// CARMEN content with the original timestamps; sarmap-log-eval-relations prints the metric.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "sarmap/laser_scan_t.hpp"
#include "sarmap/odometry_t.hpp"

namespace {

std::string RunCommand(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[512];
  while (fgets(buf, sizeof(buf), p)) out += buf;
  pclose(p);
  return out;
}

TEST(LogToolsTest, ImportCarmenWritesOdometryAndScansWithOriginalTimestamps) {
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream f(dir + "/tiny.log");
    f << "# tiny\n"
         "ODOM 1.0 2.0 0.5 0.1 0.2 0 976052857.337284 host 976052857.337284\n"
         "RAWLASER1 0 -1.570796 3.141593 1.570796 80.00 0.01 0 3 1.5 80.0 2.5 0 976052857.40 host "
         "0\n"
         "FLASER 3 1.0 2.0 3.0 9 9 9 1.5 2.5 0.25 976052857.5 host 0.1\n"
         "RAWLASER1 garbage\n";
  }
  const std::string bin = SARMAP_BIN_DIR;
  const std::string out = RunCommand(bin + "/sarmap-log-import-carmen " + dir + "/tiny.log " + dir +
                                     "/tiny.lcmlog 2>&1");
  EXPECT_NE(out.find("2 odometry, 2 scans"), std::string::npos) << out;
  EXPECT_NE(out.find("1 malformed"), std::string::npos) << out;
  lcm::LogFile log(dir + "/tiny.lcmlog", "r");
  ASSERT_TRUE(log.good());
  std::vector<std::string> channels;
  std::vector<int64_t> stamps;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    channels.push_back(ev->channel);
    stamps.push_back(ev->timestamp);
    if (ev->channel == "SCAN" && channels.size() == 2) {
      sarmap::laser_scan_t scan;
      ASSERT_EQ(scan.decode(ev->data, 0, ev->datalen), ev->datalen);
      EXPECT_EQ(scan.header.utime, 976052857400000);
      ASSERT_EQ(scan.num_ranges, 3);
      EXPECT_FLOAT_EQ(scan.ranges_m[0], 1.5f);
      EXPECT_GT(scan.ranges_m[1], scan.range_max_m);  // CARMEN's max reading: no return
      EXPECT_NEAR(scan.angle_increment_rad, M_PI / 2, 1e-6);
    }
    if (ev->channel == "ODOM" && channels.size() == 1) {
      sarmap::odometry_t odom;
      ASSERT_EQ(odom.decode(ev->data, 0, ev->datalen), ev->datalen);
      EXPECT_EQ(odom.header.utime, 976052857337284);
      EXPECT_DOUBLE_EQ(odom.position_m[0], 1.0);
      EXPECT_NEAR(2 * std::atan2(odom.orientation[3], odom.orientation[0]), 0.5, 1e-12);
    }
  }
  // ODOM, SCAN, then the FLASER's odometry and scan.
  EXPECT_EQ(channels, (std::vector<std::string>{"ODOM", "SCAN", "ODOM", "SCAN"}));
  EXPECT_EQ(stamps[2], 976052857500000);
}

TEST(LogToolsTest, InterlaceCarmenWritesScansWithTheirOwnGeometry) {
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream f(dir + "/plain.log");
    f << "# plain\n"
         "PARAM robot_width 0.5 host 0\n"
         "ODOM 1.0 2.0 0.5 0.1 0.2 0 100.0 host 100.0\n";
    for (int k = 0; k < 4; ++k) {
      f << "RAWLASER1 0 -1.570796 3.141593 0.785398 80.00 0.01 0 5 1 2 3 4 5 0 " << 100.1 + 0.1 * k
        << " host 0\n";
    }
    f << "FLASER 3 1.0 2.0 3.0 9 9 9 1.5 2.5 0.25 100.5 host 0.1\n";
  }
  const std::string bin = SARMAP_BIN_DIR;
  const std::string out = RunCommand(bin + "/sarmap-log-interlace-carmen " + dir + "/plain.log " +
                                     dir + "/interlaced.log 2>&1");
  EXPECT_NE(out.find("5 scans interlaced, 2 odometry lines"), std::string::npos) << out;
  std::ifstream in(dir + "/interlaced.log");
  std::vector<std::string> types, scans;
  std::string line;
  while (std::getline(in, line)) {
    types.push_back(line.substr(0, line.find(' ')));
    if (types.back() == "RAWLASER1") scans.push_back(line);
  }
  // Comments and other lines are copied; FLASER's odometry becomes an ODOM line before its scan.
  EXPECT_EQ(types, (std::vector<std::string>{"#", "#", "PARAM", "ODOM", "RAWLASER1", "RAWLASER1",
                                             "RAWLASER1", "RAWLASER1", "ODOM", "RAWLASER1"}));
  ASSERT_EQ(scans.size(), 5u);
  // start angle, resolution, count and readings of each phase
  const auto fields = [](const std::string& l) {
    std::istringstream s(l);
    std::vector<std::string> f;
    std::string w;
    while (s >> w) f.push_back(w);
    return f;
  };
  const auto f0 = fields(scans[0]), f1 = fields(scans[1]), f2 = fields(scans[2]),
             f3 = fields(scans[3]);
  EXPECT_NEAR(std::stod(f0[2]), -1.570796, 1e-6);
  EXPECT_EQ(f0[8], "5");
  EXPECT_NEAR(std::stod(f1[2]), -1.570796 + 0.785398, 1e-6);
  EXPECT_EQ(f1[8], "4");
  EXPECT_EQ(f1[9], "2");
  EXPECT_NEAR(std::stod(f2[4]), 2 * 0.785398, 1e-6);
  EXPECT_EQ(f2[8], "3");
  EXPECT_EQ(f2[10], "3");
  EXPECT_NEAR(std::stod(f3[2]), -1.570796 + 0.785398, 1e-6);
  EXPECT_EQ(f3[8], "2");
  EXPECT_EQ(f3[10], "4");
  EXPECT_EQ(fields(scans[4])[8], "3");  // the FLASER (phase 4 % 4 = 0): all its readings
}

TEST(LogToolsTest, InterlaceCarmenDrivesLapsWithContinuousTimeAndOdometry) {
  const std::string dir = ::testing::TempDir();
  {
    // The robot drives 1 m along x, turning by 0.5 rad; the stamps run back once (0.3 -> 0.25).
    std::ofstream f(dir + "/lap.log");
    f << "ODOM 0 0 0 0 0 0 10.0 host 10.0\n"
         "RAWLASER1 0 -1.570796 3.141593 0.785398 80.00 0.01 0 5 1 2 3 4 5 0 10.3 host 0\n"
         "RAWLASER1 0 -1.570796 3.141593 0.785398 80.00 0.01 0 5 1 2 3 4 5 0 10.25 host 0\n"
         "ODOM 1 0 0.5 0 0 0 11.0 host 11.0\n";
    std::ofstream r(dir + "/lap.relations");
    r << "10.0 11.0 1 0 0 0 0 0.5\n";
  }
  const std::string bin = SARMAP_BIN_DIR;
  const std::string out =
      RunCommand(bin + "/sarmap-log-interlace-carmen " + dir + "/lap.log " + dir +
                 "/laps.log --laps 3 --relations " + dir + "/lap.relations --relations-output " +
                 dir + "/laps.relations 2>&1");
  EXPECT_NE(out.find("6 scans interlaced, 6 odometry lines"), std::string::npos) << out;
  EXPECT_NE(out.find("3 laps of 2.0 s"), std::string::npos) << out;  // 10.0 .. 11.0, + 1 s
  std::ifstream in(dir + "/laps.log");
  std::vector<std::vector<double>> odometry;  // x y theta t
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string type;
    s >> type;
    if (type != "ODOM") continue;
    double x, y, theta, tv, rv, accel, t;
    s >> x >> y >> theta >> tv >> rv >> accel >> t;
    odometry.push_back({x, y, theta, t});
  }
  ASSERT_EQ(odometry.size(), 6u);
  // Lap k starts where lap k - 1 ended, 1 s after its latest stamp.
  for (int lap = 1; lap < 3; ++lap) {
    const auto& end = odometry[2 * lap - 1];
    const auto& start = odometry[2 * lap];
    EXPECT_NEAR(start[0], end[0], 1e-6);
    EXPECT_NEAR(start[1], end[1], 1e-6);
    EXPECT_NEAR(start[2], end[2], 1e-6);
    EXPECT_NEAR(start[3], 10.0 + 2.0 * lap, 1e-6);
  }
  // Lap 1 drives its 1 m along its own heading (0.5 rad at its start).
  EXPECT_NEAR(odometry[3][0], 1 + std::cos(0.5), 1e-6);
  EXPECT_NEAR(odometry[3][1], std::sin(0.5), 1e-6);
  EXPECT_NEAR(odometry[3][2], 1.0, 1e-6);
  std::ifstream rel(dir + "/laps.relations");
  std::vector<std::string> relations;
  while (std::getline(rel, line)) relations.push_back(line);
  ASSERT_EQ(relations.size(), 3u);
  EXPECT_EQ(relations[2], "14.000000 15.000000 1 0 0 0 0 0.5");
}

TEST(LogToolsTest, EvalRelationsPrintsTheFourMetricsAndAPlot) {
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream t(dir + "/traj.txt");
    t << "# t x y yaw\n0 0 0 0\n1 1.1 0 0\n2 2.2 0 0\n";
    std::ofstream r(dir + "/rel.relations");
    r << "0 1 1 0 0 0 0 0\n1 2 1 0 0 0 0 0\n";
  }
  const std::string bin = SARMAP_BIN_DIR;
  const std::string out =
      RunCommand(bin + "/sarmap-log-eval-relations " + dir + "/traj.txt " + dir +
                 "/rel.relations --plot " + dir + "/traj.png 2>/dev/null");
  EXPECT_NE(out.find("relations used 2, missing 0"), std::string::npos) << out;
  EXPECT_NE(out.find("abs trans [m]    0.1000 +- 0.0000"), std::string::npos) << out;
  EXPECT_NE(out.find("sq trans  [m^2]  0.0100"), std::string::npos) << out;
  EXPECT_NE(out.find("abs rot   [deg]  0.000"), std::string::npos) << out;
  EXPECT_TRUE(std::ifstream(dir + "/traj.png").good());
}

}  // namespace
