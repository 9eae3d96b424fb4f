// One-way publish-to-callback latency over LCM udpm on loopback, between two processes:
// a small message (pose_t) at 100 Hz and a compressed 640x480 depth frame at 30 Hz.
// Sender and receiver share the machine's steady clock; header.utime carries the send time.
#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <thread>

#include "common/image_messages.h"
#include "common/node.h"
#include "tests/process.h"

int main() {
  using namespace std::chrono;
  const int count = 300;
  sarmap::testing::Process sink({"sarmap-test-peer", "latency-sink", "--count", std::to_string(count)},
                                "/tmp/sarmap-latency-sink-" + std::to_string(getpid()) + ".log");
  lcm::LCM lcm(sarmap::common::DefaultLcmUrl());
  if (!lcm.good()) {
    fprintf(stderr, "LCM init failed\n");
    return 1;
  }
  for (int i = 0; i < 300 && sink.Output().find("ready") == std::string::npos; ++i) {
    std::this_thread::sleep_for(milliseconds(10));
  }
  std::this_thread::sleep_for(milliseconds(200));
  const auto steady_us = [] {
    return duration_cast<microseconds>(steady_clock::now().time_since_epoch()).count();
  };
  sarmap::pose_t pose{};
  pose.orientation[0] = 1;
  pose.header.frame = "map";
  for (int i = 0; i < count; ++i) {
    pose.header.seq = i;
    pose.header.utime = steady_us();
    lcm.publish("LAT_POSE", &pose);
    std::this_thread::sleep_for(milliseconds(10));
  }
  std::vector<uint16_t> depth(640 * 480);
  std::mt19937 rng(1);
  for (size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<uint16_t>(1000 + (i % 640) + rng() % 8);
  sarmap::header_t header{};
  header.frame = "camera";
  auto image = sarmap::common::MakeDepthImage(header, {}, depth.data(), 640, 480);
  for (int i = 0; i < count; ++i) {
    image.header.seq = i;
    image.header.utime = steady_us();  // stamped after compression: transport latency only
    lcm.publish("LAT_DEPTH", &image);
    std::this_thread::sleep_for(microseconds(33333));
  }
  sink.Wait(30);
  printf("LCM udpm one-way latency on loopback (%d messages each; depth frame %d kB compressed):\n%s",
         count, image.size / 1000, sink.Output().substr(sink.Output().find("ready") + 6).c_str());
  return 0;
}
