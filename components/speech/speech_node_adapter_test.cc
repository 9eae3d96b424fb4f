// SpeechNode in-process over memq://: the audio stream checks (another device, the wrong sample
// rate or channel count, a repeated block) drop and count; good blocks reach the speech chain.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "speech/speech_node.h"

namespace sarmap {
namespace speech {
namespace {

// `frames` of quiet noise on `channels` channels, starting at `first_sample`.
audio_frame_t Block(const std::string& device, int rate_hz, int channels, int64_t first_sample,
                    int frames) {
  audio_frame_t m{};
  m.header.utime = 1'000'000 + first_sample * 1'000'000 / rate_hz;
  m.header.frame = "mic_array";
  m.device_id = device;
  m.sample_rate_hz = rate_hz;
  m.num_channels = channels;
  m.num_samples = frames;
  m.first_sample_index = first_sample;
  m.sample_format = audio_frame_t::SAMPLE_INT16;
  m.num_values = channels * frames;
  m.samples.resize(m.num_values);
  uint32_t state = 12345;
  for (auto& s : m.samples) {
    state = state * 1664525u + 1013904223u;
    s = static_cast<int16_t>((state >> 16) % 64) - 32;
  }
  return m;
}

TEST(SpeechNodeTest, AudioOfAnotherDeviceRateOrChannelCountAndRepeatedBlocksAreDropped) {
  common::Node node("speech_node_test", "memq://");
  SpeechNode adapter(SpeechNodeOptions(), &node);  // the ReSpeaker 4-mic array at 16 kHz
  auto audio = node.Advertise<audio_frame_t>("AUDIO");
  const auto send = [&](audio_frame_t m) {
    audio.Publish(&m);
    for (int i = 0; i < 3; ++i) node.SpinOnce(0.001);
  };
  const int n = 1024;
  send(Block("respeaker", 16000, 4, 0, n));  // the first device heard is the one listened to
  send(Block("respeaker", 16000, 4, n, n));
  EXPECT_EQ(adapter.dropped(), 0);
  send(Block("other-card", 16000, 4, 2 * n, n));
  EXPECT_EQ(adapter.dropped(), 1);
  send(Block("respeaker", 48000, 4, 2 * n, n));
  EXPECT_EQ(adapter.dropped(), 2);
  send(Block("respeaker", 16000, 2, 2 * n, n));
  EXPECT_EQ(adapter.dropped(), 3);
  send(Block("respeaker", 16000, 4, n, n));  // repeats a block already processed
  EXPECT_EQ(adapter.dropped(), 4);
  send(Block("respeaker", 16000, 4, 2 * n, n));  // the stream goes on
  EXPECT_EQ(adapter.dropped(), 4);
  EXPECT_EQ(adapter.events(), 0);  // quiet noise: no speech
  EXPECT_EQ(node.stats().at("AUDIO").received, 7);
}

}  // namespace
}  // namespace speech
}  // namespace sarmap
