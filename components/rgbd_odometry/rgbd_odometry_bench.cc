// RgbdOdometry speed per frame on the real TUM fr1/xyz frames (640x480), per method, at full
// and half resolution. "Track": a frame aligned to the keyframe (the usual case);
// "TrackAndKeyframe": every frame also becomes the keyframe (the worst case).
// Run: build-*/bin/bench_rgbd_odometry (one core: taskset -c 1 ...).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "rgbd_odometry/rgbd_odometry.h"

namespace {

using namespace sarmap::rgbd_odometry;

const std::vector<std::string> kMethods = {"rgbd", "icp", "rgbd_icp", "fast_icp"};

bool Load(const std::string& dir, const std::string& which, RgbdFrame* f) {
  const cv::Mat bgr = cv::imread(dir + "/img_" + which + ".png", cv::IMREAD_COLOR);
  const cv::Mat depth = cv::imread(dir + "/dep_" + which + ".png", cv::IMREAD_ANYDEPTH);
  if (bgr.empty() || depth.empty() || depth.type() != CV_16UC1) return false;
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  f->width = depth.cols;
  f->height = depth.rows;
  f->depth.assign(depth.begin<uint16_t>(), depth.end<uint16_t>());
  f->depth_unit_m = 1.0 / 5000;
  f->image.assign(rgb.data, rgb.data + rgb.total() * 3);
  f->image_channels = 3;
  f->camera = {525.0, 525.0, 319.5, 239.5};
  return true;
}

void Run(benchmark::State& state, bool every_keyframe) {
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/depth/tum_fr1xyz_pairs/case_1";
  RgbdFrame frames[2];
  if (!Load(dir, "prev", &frames[0]) || !Load(dir, "curr", &frames[1])) {
    state.SkipWithError(("shared data missing: " + dir).c_str());
    return;
  }
  RgbdOdometryOptions o;
  o.method = kMethods[state.range(0)];
  o.image_scale = state.range(1) / 100.0;
  if (every_keyframe) {
    o.keyframe_translation_m = 1e-6;
    o.keyframe_rotation_deg = 1e-6;
  }
  RgbdOdometry odo(o);
  int64_t utime = 1000000;
  frames[0].utime = utime;
  odo.Process(frames[0]);
  int64_t i = 1, lost = 0;
  for (auto _ : state) {
    RgbdFrame& f = frames[i % 2];
    f.utime = (utime += 33333);
    const RgbdOdometryResult r = odo.Process(f);
    lost += !r.ok();
    ++i;
  }
  state.SetLabel(o.method + (o.image_scale == 1.0 ? " full" : " half") +
                 (lost ? " (" + std::to_string(lost) + " lost)" : std::string()));
}

void BM_Track(benchmark::State& state) { Run(state, false); }
void BM_TrackAndKeyframe(benchmark::State& state) { Run(state, true); }

void Args(benchmark::internal::Benchmark* b) {
  for (int m = 0; m < static_cast<int>(kMethods.size()); ++m) {
    b->Args({m, 100});
    b->Args({m, 50});
  }
  b->ArgNames({"method", "scale%"})->Unit(benchmark::kMillisecond);
}
BENCHMARK(BM_Track)->Apply(Args);
BENCHMARK(BM_TrackAndKeyframe)->Apply(Args);

}  // namespace
