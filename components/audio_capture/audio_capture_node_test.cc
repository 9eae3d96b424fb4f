// AudioCaptureNode in-process over memq://: a file becomes contiguous AUDIO blocks on the bus,
// the node stops at its end; a missing file is an options error.
#include "audio_capture/audio_capture_node.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "audio_capture/audio_file.h"
#include "common/options.h"

namespace sarmap {
namespace audio {
namespace {

TEST(AudioCaptureNodeTest, AFileBecomesContiguousBlocksAndTheNodeStopsAtItsEnd) {
  AudioBuffer b;
  b.sample_rate_hz = 16000;
  b.channels.assign(4, std::vector<float>(8000, 0.0f));
  for (int i = 0; i < 8000; ++i) b.channels[0][i] = 0.3f * std::sin(2 * M_PI * 440 * i / 16000.0);
  const std::string path =
      (std::filesystem::temp_directory_path() / "sarmap_capture_node_test.wav").string();
  WriteWav(path, b);

  common::Node node("audio_capture_node_test", "memq://");
  std::vector<audio_frame_t> blocks;
  node.Subscribe<audio_frame_t>(
      "AUDIO", [&](const audio_frame_t& m, const auto&) { blocks.push_back(m); }, 100);
  CaptureOptions options;
  options.file = path;
  options.speed = 0;
  options.start_utime = 1'000'000;
  AudioCaptureNode adapter(options, &node);
  EXPECT_EQ(node.Run(), 0);  // returns when the file ends
  while (node.lcm().handleTimeout(0) > 0) {
  }
  std::filesystem::remove(path);
  ASSERT_EQ(static_cast<int64_t>(blocks.size()), adapter.published());
  ASSERT_GT(blocks.size(), 1u);
  int64_t expected = 0;
  for (const auto& m : blocks) {
    EXPECT_EQ(m.first_sample_index, expected);
    EXPECT_EQ(m.header.utime, 1'000'000 + expected * 1'000'000 / 16000);
    EXPECT_EQ(m.num_channels, 4);
    EXPECT_EQ(m.device_id, "sarmap_capture_node_test");
    expected += m.num_samples;
  }
  EXPECT_EQ(expected, 8000);
}

TEST(AudioCaptureNodeTest, AMissingFileIsAnOptionsError) {
  common::Node node("audio_capture_node_test", "memq://");
  CaptureOptions options;
  options.file = "/nonexistent/recording.wav";
  EXPECT_THROW(AudioCaptureNode(options, &node), common::OptionsError);
}

}  // namespace
}  // namespace audio
}  // namespace sarmap
