// Encode + compress + decode of a 640x480 depth frame (lossless) and of a colour frame (JPEG),
// including the LCM encode/decode of the image_t message.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "common/decode.h"
#include "common/image_codec.h"
#include "common/image_messages.h"
#include <opencv2/imgcodecs.hpp>

namespace {

constexpr int kWidth = 640, kHeight = 480;

// A Kinect-like scene: a floor plane, a wall, a box, quantised noise and invalid pixels.
std::vector<uint16_t> KinectLikeDepth() {
  std::vector<uint16_t> depth(kWidth * kHeight);
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      double z = 3000.0;                                          // wall at 3 m
      if (r > 300) z = std::min(z, 1000.0 * 240.0 / (r - 240));  // floor
      if (c > 200 && c < 350 && r > 150 && r < 380) z = 1800.0;   // box
      z += noise(rng) * 0.0028 * z * z / 1000.0;                  // sigma ~ z^2
      depth[r * kWidth + c] = (rng() % 50 == 0) ? 0 : static_cast<uint16_t>(z);
    }
  }
  return depth;
}

std::vector<uint8_t> ColourScene() {
  std::vector<uint8_t> rgb(kWidth * kHeight * 3);
  std::mt19937 rng(2);
  for (int r = 0; r < kHeight; ++r)
    for (int c = 0; c < kWidth; ++c)
      for (int k = 0; k < 3; ++k)
        rgb[(r * kWidth + c) * 3 + k] =
            static_cast<uint8_t>(((r / 40 + c / 40) % 2) * 120 + k * 30 + rng() % 16);
  return rgb;
}

void BM_DepthEncodeCompressDecode(benchmark::State& state) {
  const auto depth = KinectLikeDepth();
  sarmap::header_t header{};
  sarmap::camera_intrinsics_t intr{};
  std::vector<uint8_t> wire;
  std::vector<uint16_t> back;
  std::string error;
  size_t bytes = 0;
  for (auto _ : state) {
    auto msg = sarmap::common::MakeDepthImage(header, intr, depth.data(), kWidth, kHeight);
    wire.resize(msg.getEncodedSize());
    msg.encode(wire.data(), 0, static_cast<int>(wire.size()));
    sarmap::image_t received;
    if (!sarmap::common::DecodeMessage(wire.data(), wire.size(), &received, &error)) {
      state.SkipWithError(error.c_str());
    }
    if (!sarmap::common::DecodeDepthImage(received, &back, &error)) state.SkipWithError(error.c_str());
    bytes = wire.size();
  }
  state.counters["wire_kB"] = bytes / 1000.0;
  state.counters["ratio"] = depth.size() * 2.0 / bytes;
}
BENCHMARK(BM_DepthEncodeCompressDecode)->Unit(benchmark::kMillisecond);

void BM_ColourJpegEncodeDecode(benchmark::State& state) {
  const auto rgb = ColourScene();
  sarmap::header_t header{};
  sarmap::camera_intrinsics_t intr{};
  std::vector<uint8_t> wire, back;
  std::string error;
  size_t bytes = 0;
  for (auto _ : state) {
    auto msg = sarmap::common::MakeColorImage(header, intr, rgb.data(), kWidth, kHeight, 85);
    wire.resize(msg.getEncodedSize());
    msg.encode(wire.data(), 0, static_cast<int>(wire.size()));
    sarmap::image_t received;
    if (!sarmap::common::DecodeMessage(wire.data(), wire.size(), &received, &error)) {
      state.SkipWithError(error.c_str());
    }
    if (!sarmap::common::DecodeColorImage(received, &back, &error)) state.SkipWithError(error.c_str());
    bytes = wire.size();
  }
  state.counters["wire_kB"] = bytes / 1000.0;
}
BENCHMARK(BM_ColourJpegEncodeDecode)->Unit(benchmark::kMillisecond);

// Real Kinect frames (shared/data/depth/kinect_slambook2_ch5), when present.
void BM_DepthRealKinectFrames(benchmark::State& state) {
  std::vector<cv::Mat> frames;
  for (int i = 1; i <= 5; ++i) {
    cv::Mat m = cv::imread(std::string(SARMAP_DATA_DIR) + "/depth/kinect_slambook2_ch5/depth/" +
                           std::to_string(i) + ".pgm", cv::IMREAD_ANYDEPTH);
    if (!m.empty() && m.type() == CV_16UC1 && m.isContinuous()) frames.push_back(m);
  }
  if (frames.empty()) {
    state.SkipWithError("shared data missing: depth/kinect_slambook2_ch5");
    return;
  }
  sarmap::header_t header{};
  std::vector<uint16_t> back;
  std::string error;
  size_t bytes = 0, raw = 0, i = 0;
  for (auto _ : state) {
    const cv::Mat& f = frames[i++ % frames.size()];
    auto msg = sarmap::common::MakeDepthImage(header, {}, f.ptr<uint16_t>(), f.cols, f.rows);
    if (!sarmap::common::DecodeDepthImage(msg, &back, &error)) state.SkipWithError(error.c_str());
    bytes += msg.data.size();
    raw += f.total() * 2;
  }
  state.counters["ratio"] = static_cast<double>(raw) / bytes;
  state.counters["wire_kB"] = bytes / 1000.0 / state.iterations();
}
BENCHMARK(BM_DepthRealKinectFrames)->Unit(benchmark::kMillisecond);

}  // namespace
