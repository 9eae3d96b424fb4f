// CPU seconds per simulated second of scenario 1 (lab_lit: depth + colour at 30 Hz, 4-channel
// Kinect array audio with reverberation), on one core, including image encoding.
//   bench_sim [world.yaml] [simulated seconds]
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/renderer.h"
#include "sim/simulator.h"

namespace {
struct CountingSink : sarmap::sim::SimSink {
  long odom = 0, images = 0, audio = 0, truth = 0;
  size_t bytes = 0;
  void Publish(const std::string&, const sarmap::odometry_t&) override { ++odom; }
  void Publish(const std::string&, const sarmap::image_t& m) override {
    ++images;
    bytes += m.data.size();
  }
  void Publish(const std::string&, const sarmap::audio_frame_t&) override { ++audio; }
  void Publish(const std::string&, const sarmap::sim_truth_t&) override { ++truth; }
  void Publish(const std::string&, const sarmap::occupancy_grid_t&) override {}
};
double ProcessCpu() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace sarmap::sim;
  const std::string world = argc > 1 ? argv[1] : std::string(SARMAP_SOURCE_DIR) + "/config/worlds/lab_lit.yaml";
  const double seconds = argc > 2 ? std::atof(argv[2]) : 10.0;
  SimOptions options;
  options.world = world;
  options.robot_config = std::string(SARMAP_SOURCE_DIR) + "/config/robot.yaml";
  options.data_dir = SARMAP_DATA_DIR;
  const double setup0 = ProcessCpu();
  Simulator sim(LoadSetup(options, ""));
  const double setup_s = ProcessCpu() - setup0;
  for (const auto& w : sim.warnings()) std::printf("warning: %s\n", w.c_str());
  CountingSink sink;
  const double cpu0 = ProcessCpu();
  sim.AdvanceTo(seconds, &sink);
  const double cpu = ProcessCpu() - cpu0;
  const SimTiming& t = sim.timing();
  std::printf("world %s, %.1f simulated s, start-up %.2f CPU s\n", world.c_str(), seconds, setup_s);
  std::printf("CPU s per simulated s: %.3f  (=> %.2fx real time on one core)\n", cpu / seconds, seconds / cpu);
  std::printf("  render %.3f  encode %.3f  audio %.3f  physics+rest %.3f  (per simulated s)\n",
              t.render_s / seconds, t.encode_s / seconds, t.audio_s / seconds,
              (cpu - t.render_s - t.encode_s - t.audio_s) / seconds);
  if (const Renderer* r = sim.renderer()) {
    const auto& rt = r->timing();
    std::printf("  per frame: raster %.2f ms, colour pass %.2f ms, depth pass %.2f ms (%ld frames)\n",
                1e3 * rt.raster_s / rt.frames, 1e3 * rt.colour_s / rt.frames, 1e3 * rt.depth_s / rt.frames,
                rt.frames);
  }
  std::printf("  messages: %ld images (%.1f kB avg), %ld audio frames, %ld odom, %ld truth\n", sink.images,
              sink.images ? sink.bytes / 1024.0 / sink.images : 0.0, sink.audio, sink.odom, sink.truth);
  return 0;
}
