// The state file's checksum and a whole sealed save, at the size SLAM's state reaches on a
// long mission (tens of MB, saved every state_save_period_s).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <random>
#include <string>

#include "common/state_file.h"

namespace {

std::string RandomBody(size_t size) {
  std::mt19937 rng(3);
  std::string body(size, '\0');
  for (char& c : body) c = static_cast<char>(rng());
  return body;
}

void BM_Crc32(benchmark::State& state) {
  const std::string body = RandomBody(static_cast<size_t>(state.range(0)) << 20);
  for (auto _ : state) {
    benchmark::DoNotOptimize(sarmap::common::Crc32(body.data(), body.size()));
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * body.size());
}
BENCHMARK(BM_Crc32)->Arg(1)->Arg(22)->Unit(benchmark::kMillisecond);

void BM_WriteSealedState(benchmark::State& state) {
  const std::string body = RandomBody(static_cast<size_t>(state.range(0)) << 20);
  const std::string path = "/tmp/sarmap_state_file_bench.state";
  for (auto _ : state) sarmap::common::WriteSealedState(path, "bench", 1, body);
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * body.size());
  std::remove(path.c_str());
}
BENCHMARK(BM_WriteSealedState)->Arg(22)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
