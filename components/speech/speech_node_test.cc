// sarmap-speech as a process over real LCM (run in a private network namespace by CTest):
// real-time AUDIO and a flood of 25 000 DOA messages, each with a new track id (5000 of them
// stamped far ahead). The node keeps its tracks bounded (evictions and dropped DOAs counted in
// NODE_STATUS) and stops promptly on SIGINT.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <thread>

#include "common/testing/isolated_network.h"
#include "sarmap/audio_frame_t.hpp"
#include "sarmap/doa_t.hpp"
#include "sarmap/node_status_t.hpp"
#include "speech/testing/kws_evaluation.h"
#include "tests/process.h"

namespace {

// CPU seconds (user + system) of process `pid` so far.
double CpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14) utime = std::stod(field);
    if (i == 15) stime = std::stod(field);
  }
  return (utime + stime) / sysconf(_SC_CLK_TCK);
}

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct StatusSink {
  std::string message;
  void OnStatus(const lcm::ReceiveBuffer*, const std::string&, const sarmap::node_status_t* m) {
    if (m->node_name == "sarmap-speech") message = m->message;
  }
};

TEST(SpeechNode, ADoaFloodOfNewTrackIdsIsBoundedAndSigintStillStopsIt) {
  if (!sarmap::IsolatedNetwork())
    GTEST_SKIP() << "run through tests/harness/sarmap-netns (ctest does)";
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  const std::string log =
      ::testing::TempDir() + "/speech-flood-" + std::to_string(getpid()) + ".log";
  sarmap::testing::Process node(
      {"sarmap-speech", "--lcm-url", url, "--config",
       std::string(SARMAP_SOURCE_DIR) + "/config/speech.yaml", "--set",
       "array=" + std::string(SARMAP_SOURCE_DIR) + "/config/arrays/respeaker4.yaml"},
      log);
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  StatusSink status;
  lcm.subscribe("NODE_STATUS", &StatusSink::OnStatus, &status);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // the keyword models load

  // Real-time audio (respeaker4: 4 channels at 16 kHz, 512-sample blocks = 32 ms): "help me"
  // every second over low noise (every beam hears speech, so a beam started for a flooded track
  // has utterances to decode), and 20 000 DOAs with new track ids over the first 2 s.
  std::vector<float> call = sarmap::speech::EspeakAvailable()
                                ? sarmap::speech::RenderEspeak("help me", "en-us", 150, 50)
                                : std::vector<float>();
  float peak = 1e-6f;
  for (float v : call) peak = std::max(peak, std::abs(v));
  const int block = 512, channels = 4;
  const int64_t t0 = 1'000'000'000;
  sarmap::audio_frame_t audio{};
  audio.header.frame = "mic_array";
  audio.device_id = "respeaker";
  audio.sample_rate_hz = 16000;
  audio.num_channels = channels;
  audio.num_samples = block;
  audio.sample_format = sarmap::audio_frame_t::SAMPLE_INT16;
  audio.num_values = block * channels;
  audio.samples.resize(audio.num_values);
  uint32_t seed = 1;
  const int kDoas = 20000, kFloodBlocks = 63, kBlocks = 125;  // flood over 2 s, 4 s of audio
  int64_t track_id = 100;
  const double cpu0 = CpuSeconds(node.pid());
  const double wall0 = Now();
  double cpu_flood = 0, wall_flood = 0;
  for (int b = 0; b < kBlocks; ++b) {
    for (int i = 0; i < block; ++i) {
      const int64_t sample = static_cast<int64_t>(b) * block + i;
      const size_t in_call = static_cast<size_t>(sample % 16000);
      const float speech = in_call < call.size() ? 8000.0f * call[in_call] / peak : 0.0f;
      for (int c = 0; c < channels; ++c) {
        const int noise =
            static_cast<int>(((seed = seed * 1664525u + 1013904223u) >> 20) % 200) - 100;
        audio.samples[static_cast<size_t>(i) * channels + c] = static_cast<int16_t>(speech + noise);
      }
    }
    audio.first_sample_index = static_cast<int64_t>(b) * block;
    audio.header.utime = t0 + audio.first_sample_index * 1'000'000 / 16000;
    lcm.publish("AUDIO", &audio);
    if (b < kFloodBlocks) {
      // At b = 10 a burst of 5000 of them stamped 11 days ahead (a track that would never time
      // out).
      const bool burst = b == 10;
      for (int k = 0;
           k < (burst ? 5000 : kDoas / kFloodBlocks + 1) && track_id < 100 + kDoas + 5000; ++k) {
        sarmap::doa_t doa{};
        doa.header.utime = audio.header.utime + (burst ? 1'000'000'000'000LL : 0);
        doa.header.frame = "mic_array";
        doa.device_id = "respeaker";
        sarmap::doa_source_t s{};
        s.track_id = track_id++;
        s.kind = sarmap::doa_source_t::KIND_AZIMUTH_ELEVATION;
        s.method = sarmap::doa_source_t::METHOD_SRP_PHAT;
        s.confidence = 1;
        s.azimuth_rad = 0.01 * (s.track_id % 600);
        s.covariance[0] = s.covariance[3] = 0.003;
        doa.sources.push_back(s);
        doa.num_sources = 1;
        lcm.publish("DOA", &doa);
      }
    }
    if (b == kFloodBlocks - 1) {
      cpu_flood = CpuSeconds(node.pid()) - cpu0;
      wall_flood = Now() - wall0;
    }
    const double until = wall0 + (b + 1) * block / 16000.0;
    while (Now() < until) lcm.handleTimeout(2);
  }
  const double cpu_all = CpuSeconds(node.pid()) - cpu0, wall_all = Now() - wall0;
  const double cpu_after = cpu_all - cpu_flood, wall_after = wall_all - wall_flood;
  for (int i = 0; i < 60; ++i) lcm.handleTimeout(20);
  std::printf("(audio %s)\n", call.empty() ? "noise only: espeak-ng missing" : "with speech");
  std::printf(
      "speech under %d DOAs with new track ids: %.0f %% CPU over the %.1f s flood, %.0f %% in "
      "the %.1f s after it; status: %s\n",
      kDoas + 5000, 100 * cpu_flood / wall_flood, wall_flood, 100 * cpu_after / wall_after,
      wall_after, status.message.c_str());
  const double sigint_s = Now();
  node.Signal(SIGINT);
  EXPECT_EQ(node.Wait(10), 0) << node.Output();
  std::printf("exited %.2f s after SIGINT\n", Now() - sigint_s);
  // Tracks bounded, evictions counted.
  const size_t tracks = status.message.find("tracks ");
  ASSERT_NE(tracks, std::string::npos) << status.message << node.Output();
  EXPECT_LE(std::stoi(status.message.substr(tracks + 7)), 16) << status.message;
  const size_t evicted = status.message.find("evicted ");
  ASSERT_NE(evicted, std::string::npos) << status.message;
  EXPECT_GT(std::stoll(status.message.substr(evicted + 8)), 0) << status.message;
  // The far-future burst is dropped (counted with the other dropped inputs).
  const size_t dropped = status.message.find("dropped ");
  ASSERT_NE(dropped, std::string::npos) << status.message;
  EXPECT_GT(std::stoll(status.message.substr(dropped + 8)), 0) << status.message;
}

}  // namespace
