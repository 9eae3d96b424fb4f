// sarmap-sound-localisation and sarmap-speech as processes over real LCM (run in a private
// network namespace by CTest): AUDIO from their device with 10 % of the blocks lost, and
// blocks of a second device interleaved. Each node keeps to the first device it heard, reports
// the second once (naming both), counts its blocks in NODE_STATUS, and bridges the gaps
// without restarting its analysis.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <string>
#include <thread>

#include "common/testing/isolated_network.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/node_status_t.hpp"
#include "tests/process.h"

namespace {

struct StatusSink {
  std::string node_name, message;
  int statuses = 0;
  void OnStatus(const lcm::ReceiveBuffer*, const std::string&, const sarmap::node_status_t* m) {
    if (m->node_name != node_name) return;
    message = m->message;
    ++statuses;
  }
};

// The integer after `key` in `text`, -1 if absent.
long long After(const std::string& text, const std::string& key) {
  const size_t at = text.find(key);
  return at == std::string::npos ? -1 : std::stoll(text.substr(at + key.size()));
}

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

void CheckNode(const std::string& program, const std::string& config) {
  if (!sarmap::IsolatedNetwork())
    GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
  ASSERT_EQ(chdir(SARMAP_SOURCE_DIR), 0);  // the configs name config/arrays/... from here
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
  const std::string log =
      ::testing::TempDir() + "/" + program + "-" + std::to_string(getpid()) + ".log";
  sarmap::testing::Process node({program, "--lcm-url", url, "--config", config}, log);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  StatusSink status{program, "", 0};
  lcm.subscribe("NODE_STATUS", &StatusSink::OnStatus, &status);
  const auto spin_until = [&](const std::function<bool()>& done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done() && std::chrono::steady_clock::now() < end) lcm.handleTimeout(20);
    return done();
  };
  ASSERT_TRUE(spin_until([&] { return status.statuses > 0 || !node.Running(); }, 30))
      << node.Output();
  ASSERT_TRUE(node.Running()) << node.Output();

  // 4 s of noise from "card0" in 512-sample blocks (16 kHz, 4 channels), 10 % lost; a block of
  // "card1" after every fifth.
  constexpr int kBlock = 512, kChannels = 4, kBlocks = 125;
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0, 2000);
  std::bernoulli_distribution lost(0.10);
  sarmap::audio_frame_t frame;
  frame.sample_rate_hz = 16000;
  frame.num_channels = kChannels;
  frame.num_samples = kBlock;
  frame.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
  frame.num_values = kBlock * kChannels;
  frame.samples.resize(frame.num_values);
  frame.overrun_samples = 0;
  int sent = 0, lost_blocks = 0, other = 0;
  for (int b = 0; b < kBlocks; ++b) {
    for (auto& v : frame.samples) v = static_cast<int16_t>(noise(rng));
    frame.header.utime = 1000000 + int64_t{b} * kBlock * 1000000 / 16000;
    frame.first_sample_index = int64_t{b} * kBlock;
    if (b > 0 && b < kBlocks - 1 && lost(rng)) {
      ++lost_blocks;
    } else {
      frame.device_id = "card0";
      lcm.publish("AUDIO", &frame);
      ++sent;
    }
    if (b % 5 == 4) {
      frame.device_id = "card1";
      lcm.publish("AUDIO", &frame);
      ++other;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(8));
  }
  ASSERT_GT(lost_blocks, 3);
  // Until the status counts every block sent (it is published once a second).
  const bool counted = spin_until(
      [&] {
        return After(status.message, "; audio blocks ") == sent &&
               After(status.message, "other devices 1 (") == other;
      },
      20);
  std::printf("%s: sent %d blocks of card0 (%d lost), %d of card1; status: %s\n", program.c_str(),
              sent, lost_blocks, other, status.message.c_str());
  EXPECT_TRUE(counted) << status.message;
  EXPECT_EQ(After(status.message, "restarts "), 0) << status.message;
  EXPECT_GT(After(status.message, "bridged gaps "), 0) << status.message;
  node.Signal(SIGINT);
  EXPECT_EQ(node.Wait(15), 0);
  const std::string out = node.Output();
  EXPECT_EQ(Count(out, "'card0', the first heard"), 1u) << out;
  EXPECT_EQ(Count(out, "second audio device 'card1'"), 1u) << out;
  EXPECT_EQ(Count(out, "restarting the analysis"), 0u) << out;
}

TEST(AudioIntakeNode, LocaliserKeepsToOneDeviceAndBridgesLostBlocks) {
  CheckNode("sarmap-sound-localisation",
            std::string(SARMAP_SOURCE_DIR) + "/config/sound_localisation.yaml");
}

TEST(AudioIntakeNode, SpeechKeepsToOneDeviceAndBridgesLostBlocks) {
  CheckNode("sarmap-speech", std::string(SARMAP_SOURCE_DIR) + "/config/speech.yaml");
}

}  // namespace
