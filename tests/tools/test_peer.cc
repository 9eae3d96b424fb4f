// sarmap-test-peer: the other end of the multi-process tests and benchmarks.
//   echo PREFIX              re-publish every message type from PREFIX<type> on PREFIX ECHO_<type>
//   stream --seconds --rate  publish synthetic 640x480 DEPTH (lossless) + RGB (JPEG) frames
//   sink --seconds           receive and decode DEPTH + RGB; print counts and gaps
//   fuzz --count             random, truncated and wrong-type payloads on every default channel
//   latency-sink --count     one-way latency of POSE / DEPTH (header.utime = sender's steady us)
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

#include "common/args.h"
#include "common/channels.h"
#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/node.h"
#include "sarmap/message_samples.h"

namespace {

using sarmap::common::Node;
using sarmap::common::ReceiveInfo;

int64_t SteadyMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch()).count();
}

int Echo(const std::string& prefix, const std::string& url) {
  Node node("sarmap-test-peer", url);
  node.SetStatusChannel("");
  lcm::LCM* lcm = &node.lcm();
#define SARMAP_ECHO(T)                                                                  \
  node.Subscribe<sarmap::T>(prefix + #T, [lcm, prefix](const sarmap::T& m, const ReceiveInfo&) { \
    lcm->publish(prefix + "ECHO_" #T, &m);                                              \
  }, 100);
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_ECHO)
#undef SARMAP_ECHO
  printf("ready\n");
  fflush(stdout);
  return node.Run();
}

sarmap::camera_intrinsics_t KinectIntrinsics() {
  sarmap::camera_intrinsics_t k{};
  k.width = 640;
  k.height = 480;
  k.fx = k.fy = 525.0;
  k.cx = 319.5;
  k.cy = 239.5;
  return k;
}

int Stream(double seconds, double rate_hz, const std::string& url) {
  Node node("sarmap-test-peer", url);
  node.SetStatusChannel("");
  auto depth_pub = node.Advertise<sarmap::image_t>("DEPTH");
  auto rgb_pub = node.Advertise<sarmap::image_t>("RGB");
  const int w = 640, h = 480;
  std::vector<uint16_t> depth(w * h);
  std::vector<uint8_t> rgb(w * h * 3);
  std::mt19937 rng(5);
  const int frames = static_cast<int>(std::lround(seconds * rate_hz));
  const auto start = std::chrono::steady_clock::now();
  for (int f = 0; f < frames; ++f) {
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        depth[r * w + c] = static_cast<uint16_t>(1500 + 2 * r + ((c + 4 * f) % 200) + rng() % 6);
        for (int k = 0; k < 3; ++k) rgb[(r * w + c) * 3 + k] = static_cast<uint8_t>((c + r + 8 * f) / 4 + 40 * k);
      }
    }
    sarmap::header_t header;
    header.utime = sarmap::common::WallClockUtime();
    header.frame = "camera";
    auto d = sarmap::common::MakeDepthImage(header, KinectIntrinsics(), depth.data(), w, h);
    auto c = sarmap::common::MakeColorImage(header, KinectIntrinsics(), rgb.data(), w, h, 85);
    depth_pub.Publish(&d);
    rgb_pub.Publish(&c);
    std::this_thread::sleep_until(start + std::chrono::duration<double>((f + 1) / rate_hz));
  }
  printf("sent %d\n", frames);
  return 0;
}

int Sink(double seconds, const std::string& url) {
  Node node("sarmap-test-peer", url);
  node.SetStatusChannel("");
  int64_t depth_count = 0, rgb_count = 0, decode_errors = 0;
  std::vector<uint16_t> depth;
  std::vector<uint8_t> rgb;
  node.Subscribe<sarmap::image_t>("DEPTH", [&](const sarmap::image_t& m, const ReceiveInfo&) {
    std::string error;
    if (sarmap::common::DecodeDepthImage(m, &depth, &error)) ++depth_count; else ++decode_errors;
  }, 300);
  node.Subscribe<sarmap::image_t>("RGB", [&](const sarmap::image_t& m, const ReceiveInfo&) {
    std::string error;
    if (sarmap::common::DecodeColorImage(m, &rgb, &error)) ++rgb_count; else ++decode_errors;
  }, 300);
  printf("ready\n");
  fflush(stdout);
  const double end = sarmap::common::SteadySeconds() + seconds;
  while (sarmap::common::SteadySeconds() < end && node.SpinOnce(0.1)) {
  }
  const auto& stats = node.stats();
  printf("depth %lld rgb %lld depth_gaps %lld rgb_gaps %lld decode_errors %lld dropped %lld\n",
         static_cast<long long>(depth_count), static_cast<long long>(rgb_count),
         static_cast<long long>(stats.at("DEPTH").sequence.gaps()),
         static_cast<long long>(stats.at("RGB").sequence.gaps()),
         static_cast<long long>(decode_errors), static_cast<long long>(node.total_dropped()));
  return 0;
}

template <class T>
std::vector<uint8_t> Encoded(std::mt19937_64& rng) {
  T m;
  sarmap::samples::Fill(m, rng);
  std::vector<uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

std::vector<uint8_t> EncodedByTypeName(const std::string& type, std::mt19937_64& rng) {
#define SARMAP_ENCODE(T) \
  if (type == #T) return Encoded<sarmap::T>(rng);
  SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_ENCODE)
#undef SARMAP_ENCODE
  return {};
}

int Fuzz(int count, const std::string& url) {
  lcm::LCM lcm(url.empty() ? sarmap::common::DefaultLcmUrl() : url);
  if (!lcm.good()) throw std::runtime_error("LCM init failed");
  std::mt19937_64 rng(11);
  int64_t sent = 0;
  for (int i = 0; i < count; ++i) {
    for (const auto& spec : sarmap::common::DefaultChannels()) {
      // 1. random bytes
      std::vector<uint8_t> junk(rng() % 600);
      for (auto& b : junk) b = static_cast<uint8_t>(rng());
      lcm.publish(spec.channel, junk.data(), static_cast<unsigned>(junk.size()));
      // 2. a valid message of the right type, truncated
      auto valid = EncodedByTypeName(spec.type, rng);
      const size_t cut = valid.size() > 1 ? rng() % (valid.size() - 1) : 0;
      lcm.publish(spec.channel, valid.data(), static_cast<unsigned>(cut));
      // 3. a valid message of another type
      const auto& other = sarmap::common::DefaultChannels()[rng() % sarmap::common::DefaultChannels().size()];
      if (std::string(other.type) != spec.type) {
        auto wrong = EncodedByTypeName(other.type, rng);
        lcm.publish(spec.channel, wrong.data(), static_cast<unsigned>(wrong.size()));
        ++sent;
      }
      sent += 2;
      std::this_thread::sleep_for(std::chrono::microseconds(300));
    }
  }
  printf("sent %lld\n", static_cast<long long>(sent));
  return 0;
}

void PrintLatency(const char* what, std::vector<double>& latencies_us) {
  if (latencies_us.empty()) {
    printf("%s: nothing received\n", what);
    return;
  }
  std::sort(latencies_us.begin(), latencies_us.end());
  const auto pct = [&](double p) { return latencies_us[std::min(latencies_us.size() - 1, static_cast<size_t>(p * latencies_us.size()))]; };
  printf("%-28s n=%-5zu median %8.1f us   p99 %8.1f us   max %8.1f us\n", what, latencies_us.size(),
         pct(0.5), pct(0.99), latencies_us.back());
}

int LatencySink(int count, const std::string& url) {
  Node node("sarmap-test-peer", url);
  node.SetStatusChannel("");
  std::vector<double> pose_us, depth_us;
  node.Subscribe<sarmap::pose_t>("LAT_POSE", [&](const sarmap::pose_t& m, const ReceiveInfo&) {
    pose_us.push_back(static_cast<double>(SteadyMicros() - m.header.utime));
  }, 1000);
  node.Subscribe<sarmap::image_t>("LAT_DEPTH", [&](const sarmap::image_t& m, const ReceiveInfo&) {
    depth_us.push_back(static_cast<double>(SteadyMicros() - m.header.utime));
  }, 1000);
  printf("ready\n");
  fflush(stdout);
  const double end = sarmap::common::SteadySeconds() + 60;
  while (static_cast<int>(pose_us.size() + depth_us.size()) < 2 * count &&
         sarmap::common::SteadySeconds() < end && node.SpinOnce(0.1)) {
  }
  PrintLatency("pose_t (small, ~0.4 kB)", pose_us);
  PrintLatency("image_t depth 640x480", depth_us);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-test-peer", [&] {
    sarmap::common::ArgParser parser("sarmap-test-peer",
                                     "Test peer process: echo | stream | sink | fuzz | latency-sink.");
    std::string mode, prefix = "RT_", url;
    double seconds = 10, rate = 30;
    int count = 100;
    parser.AddPositional("MODE", &mode, "echo | stream | sink | fuzz | latency-sink");
    parser.AddFlag("--prefix", &prefix, "echo: channel prefix");
    parser.AddFlag("--seconds", &seconds, "stream/sink duration");
    parser.AddFlag("--rate", &rate, "stream: frames per second");
    parser.AddFlag("--count", &count, "fuzz: rounds; latency-sink: messages per kind");
    parser.AddFlag("--lcm-url", &url, "LCM URL");
    if (!parser.Parse(argc, argv)) return 0;
    if (mode == "echo") return Echo(prefix, url);
    if (mode == "stream") return Stream(seconds, rate, url);
    if (mode == "sink") return Sink(seconds, url);
    if (mode == "fuzz") return Fuzz(count, url);
    if (mode == "latency-sink") return LatencySink(count, url);
    throw sarmap::common::ArgError("unknown mode '" + mode + "'");
  });
}
