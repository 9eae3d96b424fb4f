// The report never counts what is far outside the map, and its GeoTIFF reads back in GDAL with
// the map's georeference, with the people and the path where report.json says they are.
#include "log-tools/geotiff.h"

#include <gdal.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "log-tools/lcm_log_writer.h"
#include "log-tools/mission_report.h"
#include "sarmap/pose_t.hpp"

namespace sarmap {
namespace logtools {
namespace {

// A person or sound source on the map at (x, y) with `variance` on each axis.
template <class Mapped>
Mapped Placed(int64_t id, double x, double y, double variance) {
  Mapped m{};
  m.id = id;
  m.position_m[0] = x;
  m.position_m[1] = y;
  m.covariance[0] = m.covariance[4] = m.covariance[8] = variance;
  return m;
}

mapped_person_t MakePerson(int64_t id, double x, double y, int cues, double variance) {
  mapped_person_t p = Placed<mapped_person_t>(id, x, y, variance);
  p.confidence = 0.8f;
  p.cues = static_cast<int8_t>(cues);
  p.people_count = 1;
  p.sound_source_id = -1;
  return p;
}

sound_source_t MakeSource(int64_t id, double x, double y, double variance, int8_t state) {
  sound_source_t s = Placed<sound_source_t>(id, x, y, variance);
  s.state = state;
  s.has_position = true;
  return s;
}

// A 6 x 4 m map at 5 cm whose origin is off the metre grid, a path across it, three people
// (seen, heard, both), a person and a sound source that have not converged (the sound map's
// (773, 638) m with variance 4e9 m^2), and one heard person inside the map but with a 40 m std.
std::string WriteMission(const std::string& name) {
  const std::string path = ::testing::TempDir() + "/" + name + ".lcmlog";
  logtools::LcmLogWriter log(path);
  occupancy_grid_t grid{};
  grid.header.frame = "map";
  grid.resolution_m = 0.05;
  grid.width = 120;
  grid.height = 80;
  grid.origin_x_m = -1.3;
  grid.origin_y_m = -0.7;
  grid.data.assign(120 * 80, 0);
  for (int x = 0; x < 120; ++x) grid.data[x] = grid.data[79 * 120 + x] = 100;
  for (int y = 0; y < 10; ++y) {
    for (int x = 100; x < 120; ++x) grid.data[y * 120 + x] = static_cast<uint8_t>(-1);
  }
  grid.size = static_cast<int32_t>(grid.data.size());
  log.Write("MAP", grid, 1'000'000);
  for (int i = 0; i < 40; ++i) {
    pose_t pose{};
    pose.header.utime = 1'000'000 + i * 100'000;
    pose.position_m[0] = 0.1 * i + 0.013;  // off the pixel corners
    pose.position_m[1] = 0.05 * i + 0.021;
    pose.orientation[0] = std::cos(0.2);
    pose.orientation[3] = std::sin(0.2);
    log.Write("POSE", pose, pose.header.utime);
  }
  people_map_t people{};
  people.header.frame = "map";
  people.people = {
      MakePerson(1, 1.0, 2.5, mapped_person_t::CUE_SEEN_RGBD, 0.01),
      MakePerson(2, 3.2, 0.4, mapped_person_t::CUE_HEARD, 0.09),
      MakePerson(3, -0.5, 2.0, mapped_person_t::CUE_SEEN_RGBD | mapped_person_t::CUE_HEARD, 0.04),
      MakePerson(4, 773.0, 638.0, mapped_person_t::CUE_HEARD, 4e9),
      MakePerson(5, 2.0, 1.0, mapped_person_t::CUE_HEARD, 1600.0)};
  people.num_people = 5;
  log.Write("PEOPLE_MAP", people, 4'000'000);
  sound_map_t sounds{};
  sounds.header.frame = "map";
  sounds.sources = {MakeSource(1, 3.2, 0.45, 0.04, sound_source_t::STATE_CONVERGED),
                    MakeSource(2, 773.0, 638.0, 4e9, sound_source_t::STATE_INITIALISING)};
  sounds.num_sources = 2;
  log.Write("SOUND_MAP", sounds, 4'000'000);
  return path;
}

TEST(ReportOutsideMapTest, FarAndUnconvergedEstimatesAreListedApartNeverFound) {
  const MissionData data = LoadMission(WriteMission("outside"));
  const MissionSummary s = Summarise(data, 0.5);
  EXPECT_EQ(s.people_found, 3);
  EXPECT_EQ(s.sources_mapped, 1);
  ASSERT_EQ(s.outside_map.size(), 3u);
  EXPECT_EQ(s.outside_map[0].kind, "person");
  EXPECT_EQ(s.outside_map[0].id, 4);
  EXPECT_EQ(s.outside_map[0].why, "outside the map");
  EXPECT_EQ(s.outside_map[1].id, 5);  // inside the map, but a 40 m std
  EXPECT_NE(s.outside_map[1].why.find("unconverged"), std::string::npos);
  EXPECT_EQ(s.outside_map[2].kind, "sound source");
  EXPECT_NEAR(s.outside_map[2].x_m, 773.0, 1e-9);
  const std::string text = SummaryText(data, s);
  EXPECT_NE(text.find("3 people on the map, 1 sound sources"), std::string::npos) << text;
  EXPECT_EQ(text.find("person #4 at (773.00"), std::string::npos) << text;  // not among the found
  EXPECT_NE(text.find("unconverged or far outside the map"), std::string::npos) << text;
  EXPECT_NE(text.find("sound source #2 at (773.0, 638.0) m"), std::string::npos) << text;

  const std::string dir = ::testing::TempDir() + "/outside-report";
  WriteReport(data, s, dir);
  std::ifstream json_file(dir + "/report.json");
  const auto j = nlohmann::json::parse(json_file);
  ASSERT_EQ(j["people"].size(), 3u);
  for (const auto& p : j["people"]) EXPECT_LT(std::abs(p["x_m"].get<double>()), 10.0);
  EXPECT_EQ(j["sound_sources"].size(), 1u);
  EXPECT_EQ(j["outside_map"].size(), 3u);
  EXPECT_EQ(j["files"]["geotiff"], "map.tif");
  std::ifstream html_file(dir + "/report.html");
  const std::string html((std::istreambuf_iterator<char>(html_file)), {});
  EXPECT_NE(html.find("Unconverged / outside the map"), std::string::npos);
  EXPECT_NE(html.find("773.0, 638.0"), std::string::npos);
  for (const char* link : {"href=\"map.png\"", "href=\"map.tif\"", "href=\"report.json\""}) {
    EXPECT_NE(html.find(link), std::string::npos) << link;
  }
}

std::array<uint8_t, 3> PixelAt(GDALDatasetH ds, const double (&g)[6], double x, double y) {
  // Inverse of the (unrotated) geotransform: the pixel whose square holds (x, y).
  const int col = static_cast<int>(std::floor((x - g[0]) / g[1]));
  const int row = static_cast<int>(std::floor((y - g[3]) / g[5]));
  std::array<uint8_t, 3> rgb{};
  for (int b = 0; b < 3; ++b) {
    EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(ds, b + 1), GF_Read, col, row, 1, 1, &rgb[b], 1, 1,
                           GDT_Byte, 0, 0),
              CE_None);
  }
  return rgb;
}

TEST(GeoTiffTest, ReadsBackInGdalWithTheReportsPositions) {
  const std::string log = WriteMission("geotiff");
  const MissionData data = LoadMission(log);
  const MissionSummary s = Summarise(data, 0.5);
  const std::string dir = ::testing::TempDir() + "/geotiff-report";
  WriteReport(data, s, dir);
  const std::string tif = dir + "/map.tif";
  GDALAllRegister();
  GDALDatasetH ds = GDALOpen(tif.c_str(), GA_ReadOnly);
  ASSERT_NE(ds, nullptr);
  EXPECT_STREQ(GDALGetDriverShortName(GDALGetDatasetDriver(ds)), "GTiff");
  EXPECT_EQ(GDALGetRasterXSize(ds), 120);
  EXPECT_EQ(GDALGetRasterYSize(ds), 80);
  EXPECT_EQ(GDALGetRasterCount(ds), 3);
  double g[6];
  ASSERT_EQ(GDALGetGeoTransform(ds, g), CE_None);
  // Pixel size = map resolution; the top-left corner is the grid's origin plus its height.
  EXPECT_NEAR(g[0], -1.3, 1e-9);
  EXPECT_NEAR(g[1], 0.05, 1e-12);
  EXPECT_NEAR(g[2], 0.0, 1e-12);
  EXPECT_NEAR(g[3], -0.7 + 80 * 0.05, 1e-9);
  EXPECT_NEAR(g[4], 0.0, 1e-12);
  EXPECT_NEAR(g[5], -0.05, 1e-12);
  EXPECT_NE(std::string(GDALGetProjectionRef(ds)).find("sarmap map frame"), std::string::npos)
      << GDALGetProjectionRef(ds);

  // Where report.json puts them: the people in the colour of how they were found, the path in
  // the path's colour, and the map's cells.
  std::ifstream json_file(dir + "/report.json");
  const auto j = nlohmann::json::parse(json_file);
  ASSERT_EQ(j["people"].size(), 3u);
  for (const auto& p : j["people"]) {
    const std::string how = p["how"];
    const auto expected = how == "seen"           ? GeoTiffColours::kSeen
                          : how == "heard"        ? GeoTiffColours::kHeard
                          : how == "seen + heard" ? GeoTiffColours::kSeenAndHeard
                                                  : std::array<uint8_t, 3>{};
    EXPECT_EQ(PixelAt(ds, g, p["x_m"], p["y_m"]), expected) << how;
  }
  const auto& path = j["path_m"];
  ASSERT_GT(path.size(), 20u);
  int on_path = 0;
  for (size_t i = 10; i < 30; ++i)
    on_path += PixelAt(ds, g, path[i][0], path[i][1]) == GeoTiffColours::kPath;
  EXPECT_GE(on_path, 18);  // a few under a drawn person or a grid line's neighbour
  EXPECT_EQ(PixelAt(ds, g, -1.0, -0.68), GeoTiffColours::kOccupied);  // the bottom wall
  const auto unknown = PixelAt(ds, g, 4.45, -0.45);
  EXPECT_TRUE(unknown == GeoTiffColours::kUnknownA || unknown == GeoTiffColours::kUnknownB);
  // The far person and source left no pixel: nothing magenta or blue away from people 2 and 5.
  GDALClose(ds);

  // gdalinfo, as a user would check it.
  FILE* p = popen(("gdalinfo " + tif + " 2>&1").c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string info;
  char buf[512];
  while (fgets(buf, sizeof(buf), p)) info += buf;
  const int status = pclose(p);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    GTEST_SKIP() << "gdalinfo not installed (gdal-bin)";
  EXPECT_NE(info.find("Pixel Size = (0.050000000000000,-0.050000000000000)"), std::string::npos)
      << info;
  EXPECT_NE(info.find("Origin = (-1.300000000000000,3.300000000000000)"), std::string::npos)
      << info;
}

TEST(GeoTiffTest, TheToolWritesItAndSaysWhatItLeftOut) {
  const std::string log = WriteMission("geotiff-tool");
  const std::string tif = ::testing::TempDir() + "/geotiff-tool.tif";
  std::remove(tif.c_str());
  FILE* p = popen(
      (std::string(SARMAP_BIN_DIR) + "/sarmap-log-geotiff " + log + " -o " + tif + " 2>&1").c_str(),
      "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (fgets(buf, sizeof(buf), p)) out += buf;
  ASSERT_EQ(pclose(p), 0) << out;
  EXPECT_NE(out.find("120 x 80 pixels of 0.050 m, 3 people, 1 sound sources, 3 left out"),
            std::string::npos)
      << out;
  GDALAllRegister();
  GDALDatasetH ds = GDALOpen(tif.c_str(), GA_ReadOnly);
  ASSERT_NE(ds, nullptr);
  double g[6];
  ASSERT_EQ(GDALGetGeoTransform(ds, g), CE_None);
  EXPECT_EQ(PixelAt(ds, g, 1.0, 2.5), GeoTiffColours::kSeen);  // person 1
  GDALClose(ds);
}

TEST(GeoTiffTest, AMapWhoseCellsDoNotDecodeLeavesTheRestOfTheReport) {
  MissionData data;
  occupancy_grid_t grid{};
  grid.resolution_m = 0.05;
  grid.width = 10;
  grid.height = 10;
  grid.data.assign(30, 0);  // not width x height
  grid.size = 30;
  data.map = grid;
  data.trail = {{0.0, 0.0}, {1.0, 0.0}};
  const MissionSummary s = Summarise(data, 0.5);
  const std::string dir = ::testing::TempDir() + "/geotiff-bad-map";
  WriteReport(data, s, dir);
  EXPECT_FALSE(std::ifstream(dir + "/map.tif").good());
  EXPECT_TRUE(std::ifstream(dir + "/map.png").good());
  std::ifstream json_file(dir + "/report.json");
  const auto j = nlohmann::json::parse(json_file);
  EXPECT_TRUE(j["files"]["geotiff"].is_null());
  EXPECT_THROW(WriteGeoTiff(data, s, dir + "/direct.tif"), std::runtime_error);
}

}  // namespace
}  // namespace logtools
}  // namespace sarmap
