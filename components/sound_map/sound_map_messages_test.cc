// The sound map node's message conversions (sound_map_messages.h): what each input message
// becomes in the core, and what is refused.
#include "sound_map/sound_map_messages.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/compression.h"

namespace sarmap {
namespace sound_map {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

TEST(SoundMapMessagesTest, PlanarPoseIsTheHeadingOfTheXAxis) {
  sarmap::pose_t msg{};
  msg.position_m[0] = 1.5;
  msg.position_m[1] = -2.0;
  msg.position_m[2] = 0.3;
  // Yaw 0.7 rad, then a roll of 0.2 rad about the robot's x axis: the x axis keeps its heading.
  const Eigen::Quaterniond q = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX());
  msg.orientation[0] = 2 * q.w();  // not normalised: the conversion normalises
  msg.orientation[1] = 2 * q.x();
  msg.orientation[2] = 2 * q.y();
  msg.orientation[3] = 2 * q.z();
  const common::Rigid2d p = PlanarPose(msg);
  EXPECT_DOUBLE_EQ(p.translation().x(), 1.5);
  EXPECT_DOUBLE_EQ(p.translation().y(), -2.0);
  EXPECT_NEAR(p.yaw_rad(), 0.7, 1e-12);
}

TEST(SoundMapMessagesTest, DoasKeepTheirFieldsAndNonFiniteOnesAreDropped) {
  sarmap::doa_t msg{};
  sarmap::doa_source_t s{};
  s.track_id = 7;
  s.kind = sarmap::doa_source_t::KIND_AZIMUTH_ELEVATION;
  s.azimuth_rad = 1.0;
  s.elevation_rad = 0.25;
  const double cov[4] = {0.01, 0.002, 0.003, 0.04};
  for (int i = 0; i < 4; ++i) s.covariance[i] = cov[i];
  s.sound_class = sarmap::doa_source_t::SOUND_CLASS_ALARM;
  msg.sources.push_back(s);
  sarmap::doa_source_t unknown_class = s;
  unknown_class.track_id = 8;
  unknown_class.sound_class = 9;  // no such class: unknown
  msg.sources.push_back(unknown_class);
  for (int bad = 0; bad < 3; ++bad) {
    sarmap::doa_source_t b = s;
    if (bad == 0) b.azimuth_rad = kNan;
    if (bad == 1) b.elevation_rad = INFINITY;
    if (bad == 2) b.covariance[3] = kNan;
    msg.sources.push_back(b);
  }
  msg.num_sources = static_cast<int32_t>(msg.sources.size());

  const std::vector<OnlineSoundMap::Doa> doas = DoasFromMessage(msg);
  ASSERT_EQ(doas.size(), 2u);
  EXPECT_EQ(doas[0].track_id, 7);
  EXPECT_EQ(doas[0].kind, int{sarmap::doa_source_t::KIND_AZIMUTH_ELEVATION});
  EXPECT_DOUBLE_EQ(doas[0].azimuth_rad, 1.0);
  EXPECT_DOUBLE_EQ(doas[0].elevation_rad, 0.25);
  EXPECT_DOUBLE_EQ(doas[0].covariance(0, 1), 0.002);  // row-major
  EXPECT_DOUBLE_EQ(doas[0].covariance(1, 0), 0.003);
  EXPECT_DOUBLE_EQ(doas[0].covariance(1, 1), 0.04);
  EXPECT_EQ(doas[0].sound_class, int{sarmap::doa_source_t::SOUND_CLASS_ALARM});
  EXPECT_EQ(doas[1].sound_class, int{sarmap::doa_source_t::SOUND_CLASS_UNKNOWN});
}

sarmap::slam_anchors_t Anchors(int n) {
  sarmap::slam_anchors_t msg{};
  msg.current.x_m = 4;
  msg.current.y_m = 5;
  msg.current.yaw_rad = 0.5;
  msg.num_anchors = n;
  for (int i = 0; i < n; ++i) {
    sarmap::slam_anchor_t a{};
    a.node_id = 100 + i;
    a.x_m = i;
    a.y_m = -i;
    a.yaw_rad = 0.1 * i;
    msg.anchors.push_back(a);
  }
  msg.covariance_dim = 3 * (1 + n);
  msg.covariance.assign(msg.covariance_dim, std::vector<double>(msg.covariance_dim, 0.0));
  for (int i = 0; i < msg.covariance_dim; ++i) msg.covariance[i][i] = 0.01 * (i + 1);
  msg.covariance[0][1] = msg.covariance[1][0] = 0.005;
  return msg;
}

TEST(SoundMapMessagesTest, AnchorsNeedACovarianceOfTheirSize) {
  common::Rigid2d current;
  std::vector<std::pair<int64_t, common::Rigid2d>> anchors;
  Eigen::MatrixXd cov;
  ASSERT_TRUE(AnchorsFromMessage(Anchors(2), &current, &anchors, &cov));
  EXPECT_DOUBLE_EQ(current.translation().x(), 4);
  EXPECT_DOUBLE_EQ(current.yaw_rad(), 0.5);
  ASSERT_EQ(anchors.size(), 2u);
  EXPECT_EQ(anchors[1].first, 101);
  EXPECT_DOUBLE_EQ(anchors[1].second.translation().y(), -1);
  ASSERT_EQ(cov.rows(), 9);
  EXPECT_DOUBLE_EQ(cov(0, 1), 0.005);
  EXPECT_DOUBLE_EQ(cov(8, 8), 0.09);

  sarmap::slam_anchors_t wrong_dim = Anchors(2);
  wrong_dim.covariance_dim = 6;  // 3 (1 + n) is 9
  wrong_dim.covariance.resize(6, std::vector<double>(6, 0.0));
  EXPECT_FALSE(AnchorsFromMessage(wrong_dim, &current, &anchors, &cov));
  sarmap::slam_anchors_t ragged = Anchors(2);
  ragged.covariance[4].pop_back();
  EXPECT_FALSE(AnchorsFromMessage(ragged, &current, &anchors, &cov));
  sarmap::slam_anchors_t missing_anchor = Anchors(2);
  missing_anchor.anchors.pop_back();
  EXPECT_FALSE(AnchorsFromMessage(missing_anchor, &current, &anchors, &cov));
}

TEST(SoundMapMessagesTest, OnlyHeardPeopleAreDirectionsAndAKeywordIsACall) {
  sarmap::people_detections_t msg{};
  sarmap::person_detection_t heard{};
  heard.cue = sarmap::person_detection_t::CUE_HEARD;
  heard.track_id = 3;
  heard.azimuth_rad = -0.4;
  heard.direction_covariance[0] = heard.direction_covariance[3] = 0.01;
  sarmap::person_detection_t caller = heard;
  caller.track_id = -1;
  caller.keyword = "help";
  sarmap::person_detection_t seen = heard;
  seen.cue = sarmap::person_detection_t::CUE_SEEN_DEPTH;
  seen.track_id = 9;
  sarmap::person_detection_t broken = heard;
  broken.azimuth_rad = kNan;
  msg.detections = {heard, caller, seen, broken};
  msg.num_detections = 4;

  const std::vector<OnlineSoundMap::Doa> directions = HeardDirections(msg);
  ASSERT_EQ(directions.size(), 2u);
  EXPECT_DOUBLE_EQ(directions[0].azimuth_rad, -0.4);
  EXPECT_EQ(directions[0].kind, int{OnlineSoundMap::kAzimuth});
  EXPECT_FALSE(directions[0].called);
  EXPECT_TRUE(directions[1].called);
  // Track ids: heard detections with one (the caller has none; the seen one is not heard).
  EXPECT_EQ(HeardTracks(msg), (std::vector<int64_t>{3, 3}));
}

sarmap::occupancy_grid_t Grid(int width, int height) {
  sarmap::occupancy_grid_t g{};
  g.width = width;
  g.height = height;
  g.resolution_m = 0.5;
  g.origin_x_m = -1.0;
  g.origin_y_m = 2.0;
  g.data.assign(static_cast<size_t>(width) * height, static_cast<uint8_t>(-1));  // unknown
  g.size = static_cast<int32_t>(g.data.size());
  return g;
}

TEST(SoundMapMessagesTest, SiteBoxIsTheBoxOfTheKnownCells) {
  sarmap::occupancy_grid_t g = Grid(10, 8);
  Eigen::Vector2d lo, hi;
  EXPECT_FALSE(SiteBox(g, &lo, &hi));  // nothing known yet
  g.data[2 * 10 + 3] = 0;              // row 2, column 3: free
  g.data[5 * 10 + 6] = 100;            // row 5, column 6: occupied
  ASSERT_TRUE(SiteBox(g, &lo, &hi));
  EXPECT_NEAR(lo.x(), -1.0 + 0.5 * 3, 1e-12);
  EXPECT_NEAR(lo.y(), 2.0 + 0.5 * 2, 1e-12);
  EXPECT_NEAR(hi.x(), -1.0 + 0.5 * 7, 1e-12);  // the far edge of column 6
  EXPECT_NEAR(hi.y(), 2.0 + 0.5 * 6, 1e-12);

  // The same grid compressed gives the same box; a grid whose data does not fit gives none.
  sarmap::occupancy_grid_t z = g;
  z.data = common::CompressBytes(g.data.data(), g.data.size());
  z.size = static_cast<int32_t>(z.data.size());
  z.compression = sarmap::occupancy_grid_t::COMPRESSION_ZSTD;
  Eigen::Vector2d zlo, zhi;
  ASSERT_TRUE(SiteBox(z, &zlo, &zhi));
  EXPECT_EQ(zlo, lo);
  EXPECT_EQ(zhi, hi);
  sarmap::occupancy_grid_t short_data = g;
  short_data.data.pop_back();
  short_data.size -= 1;
  EXPECT_FALSE(SiteBox(short_data, &lo, &hi));
  sarmap::occupancy_grid_t no_resolution = g;
  no_resolution.resolution_m = 0;
  EXPECT_FALSE(SiteBox(no_resolution, &lo, &hi));
}

}  // namespace
}  // namespace sound_map
}  // namespace sarmap
