// sarmap-speech's input handling without the bus: DOA tracks steer the beams on the audio's
// sample clock; DOAs before any audio, of another device or of another kind are not used.
#include "speech/speech_stream.h"

#include <gtest/gtest.h>

#include "common/robot_config.h"

namespace sarmap {
namespace speech {
namespace {

sarmap::doa_t Doa(int64_t utime, int64_t track_id, int8_t kind, const std::string& device) {
  sarmap::doa_t m{};
  m.header.utime = utime;
  m.device_id = device;
  sarmap::doa_source_t s{};
  s.track_id = track_id;
  s.kind = kind;
  s.azimuth_rad = 1.0;
  s.elevation_rad = 0.2;
  s.covariance[0] = s.covariance[3] = 0.003;
  m.sources.push_back(s);
  m.num_sources = 1;
  return m;
}

TEST(SpeechStreamTest, DoaTracksSteerTheBeamsOnceAudioHasCome) {
  const std::string root = SARMAP_SOURCE_DIR;
  const auto options = common::LoadOptions<SpeechNodeOptions>(root + "/config/speech.yaml", {});
  SpeechStream stream(options, common::LoadMicArray(root + "/" + options.array));
  const int8_t kind = static_cast<int8_t>(stream.kind());
  std::vector<std::string> warnings;
  // Before any audio there is no clock to put the DOA on.
  stream.OnDoa(Doa(1'000'000, 3, kind, "mic"), "mic", &warnings);
  EXPECT_FALSE(stream.processor().has_track(3));
  int channels = 0;
  for (int c : stream.geometry().channel_map) channels = std::max(channels, c + 1);
  std::vector<int16_t> silence(512 * channels, 0);
  std::vector<sarmap::speech_event_t> events;
  std::vector<sarmap::people_detections_t> people;
  stream.OnAudio(silence.data(), 512, channels, 1'000'000, "mic", &events, &people);
  EXPECT_TRUE(events.empty());
  EXPECT_TRUE(people.empty());
  stream.OnDoa(Doa(1'010'000, 5, kind, "other"), "mic", &warnings);  // another device
  EXPECT_FALSE(stream.processor().has_track(5));
  stream.OnDoa(Doa(1'010'000, 3, kind, "mic"), "mic", &warnings);
  EXPECT_TRUE(stream.processor().has_track(3));
  EXPECT_TRUE(warnings.empty());
  stream.OnDoa(Doa(1'010'000, 4, static_cast<int8_t>(kind + 1), "mic"), "mic", &warnings);
  EXPECT_FALSE(stream.processor().has_track(4));
  EXPECT_EQ(warnings.size(), 1u);
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
