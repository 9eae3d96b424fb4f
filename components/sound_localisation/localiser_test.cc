#include "sound_localisation/localiser.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "common/robot_config.h"
#include "sound_localisation/doa_evaluation.h"

namespace sarmap {
namespace sound {
namespace {

namespace fs = std::filesystem;

ArrayGeometry LoadArray(const std::string& name) {
  return ArrayGeometry::FromOptions(common::LoadMicArray(std::string(SARMAP_SOURCE_DIR) + "/config/arrays/" + name + ".yaml"));
}

std::vector<std::string> WavFilesUnder(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().extension() == ".wav") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

// Real ReSpeaker recordings, one talker at azimuth 180, elevation 20 (folder name).
TEST(LocaliserRealData, RespeakerSingleTalkerAllMethods) {
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/audio/respeaker4/a180e20";
  if (!fs::exists(dir)) GTEST_SKIP() << "shared data missing: " << dir;
  const ArrayGeometry g = LoadArray("respeaker4");
  const auto files = WavFilesUnder(dir);
  ASSERT_EQ(files.size(), 6u);
  std::printf("| file | method | blocks | median az err | median el err | whole-file az / el |\n|---|---|---|---|---|---|\n");
  for (const std::string method : {"srp_phat", "music", "gevd_music", "gcc_phat"}) {
    LocaliserOptions o;
    o.method = method;
    o.max_sources = 1;
    std::vector<double> az, el;
    for (const auto& f : files) {
      const auto r = EvaluateDoaFile(f, g, o, {DegToRad(180), DegToRad(20)});
      std::printf("| %s | %s | %d | %.2f | %.2f | %.1f / %.1f |\n", fs::path(f).parent_path().filename().string().append("/").append(fs::path(f).filename().string()).c_str(),
                  method.c_str(), r.blocks, r.median_azimuth_error_deg, r.median_elevation_error_deg, r.whole_azimuth_deg,
                  r.whole_elevation_deg);
      EXPECT_GE(r.blocks, 5) << f;  // blocks with enough sound (0.256 s windows) in a 5.6 s file
      az.push_back(r.median_azimuth_error_deg);
      el.push_back(r.median_elevation_error_deg);
    }
    const double maz = Median(az), mel = Median(el);
    std::printf("| all files (median) | %s | | %.2f | %.2f | |\n", method.c_str(), maz, mel);
    if (std::string(method) == "srp_phat" || std::string(method) == "music") {
      EXPECT_LE(maz, 3.0) << method;
      EXPECT_LE(mel, 5.0) << method;
    }
  }
}

}  // namespace
}  // namespace sound
}  // namespace sarmap
