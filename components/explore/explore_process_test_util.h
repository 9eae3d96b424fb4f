#pragma once
// For the tests that drive the real sarmap-explore over LCM: what they publish to it and the
// key files they give it. Header-only, test code only.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <string>

#include "sarmap/laser_scan_t.hpp"

namespace sarmap {
namespace testing_util {

// A SCAN of 181 beams, one a degree across the front half-plane, every one at `range_m`.
inline laser_scan_t UniformScan(float range_m) {
  laser_scan_t scan{};
  scan.header.frame = "base";
  scan.angle_min_rad = -M_PI / 2;
  scan.angle_increment_rad = M_PI / 180;
  scan.range_min_m = 0.45f;
  scan.range_max_m = 8.0f;
  scan.ranges_m.assign(181, range_m);
  scan.num_ranges = 181;
  return scan;
}

// Writes a 32-byte key file of `fill` bytes, readable by its owner only; returns `path`.
inline std::string WriteKeyFile(const std::string& path, char fill) {
  std::ofstream(path, std::ios::binary) << std::string(32, fill);
  EXPECT_EQ(chmod(path.c_str(), 0600), 0);
  return path;
}

}  // namespace testing_util
}  // namespace sarmap
