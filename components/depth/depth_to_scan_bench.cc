// Depth-to-scan speed on a 640x480 frame (synthetic wall and floor): every row or every
// second, each bin's minimum or its nearest surface (range_noise_k).
#include <benchmark/benchmark.h>

#include <cmath>

#include "depth/depth_to_scan.h"

namespace {

void BM_DepthToScan(benchmark::State& state) {
  using namespace sarmap::depth;
  PinholeIntrinsics in{640, 480, 525, 525, 319.5, 239.5};
  Eigen::Isometry3d bc = Eigen::Isometry3d::Identity();
  bc.linear() = (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                 Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX())).toRotationMatrix();
  bc.translation() = Eigen::Vector3d(0.1, 0, 0.55);
  DepthToScanOptions o;
  o.row_step = static_cast<int>(state.range(0));
  o.range_noise_k = state.range(1) ? 1.425e-3 : 0.0;  // nearest surface or minimum
  DepthToScan conv(o, in, bc);
  std::vector<uint16_t> depth(640 * 480);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) depth[v * 640 + u] = static_cast<uint16_t>(1500 + 3 * u + v);
  for (auto _ : state) benchmark::DoNotOptimize(conv.Convert(depth.data(), 0.001));
}
BENCHMARK(BM_DepthToScan)->Args({1, 0})->Args({2, 0})->Args({2, 1})->Unit(benchmark::kMillisecond);

}  // namespace
