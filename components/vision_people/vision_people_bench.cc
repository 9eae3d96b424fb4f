// Frames per second of the people detector on one core (the process pins itself to one CPU),
// 640x480: five_people.pcd (colour + HOG, and depth only) and synthetic Kinect frames.
#include <sched.h>

#include <time.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "vision_people/hog_classifier.h"
#include "vision_people/pcd_frame.h"
#include "vision_people/synthetic_scene.h"

using namespace sarmap::vision_people;

namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
// CPU time of this thread: what one core spends, whatever else the machine runs.
double Cpu() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// Runs `detect` on the frames round-robin; prints mean ms per frame and fps.
void Run(const std::string& name, PeopleDetector* detector, const std::vector<RgbdFrame>& frames,
         int iterations) {
  for (int i = 0; i < 3; ++i) detector->Detect(frames[i % frames.size()]);  // warm up
  size_t people = 0;
  const double t0 = Now(), c0 = Cpu();
  for (int i = 0; i < iterations; ++i) people += detector->Detect(frames[i % frames.size()]).people.size();
  const double dt = (Now() - t0) / iterations, dc = (Cpu() - c0) / iterations;
  printf("%-56s cpu %6.2f ms = %6.1f fps | wall %6.2f ms = %6.1f fps | %.2f people/frame\n", name.c_str(),
         1e3 * dc, 1.0 / dc, 1e3 * dt, 1.0 / dt, static_cast<double>(people) / iterations);
}

}  // namespace

int main() {
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(0, &one);
  const bool pinned = sched_setaffinity(0, sizeof(one), &one) == 0;
  printf("vision_people benchmark, 640x480, %s; cpu = this thread's CPU time (one core), wall = elapsed\n",
         pinned ? "pinned to CPU 0" : "NOT pinned (sched_setaffinity failed)");
  {
    std::ifstream load("/proc/loadavg");
    std::string l1;
    load >> l1;
    printf("load average (1 min) %s: wall figures include waiting for the CPU\n", l1.c_str());
  }
  const std::string dir = std::string(SARMAP_DATA_DIR) + "/vision/pcl_people";
  const GroundPlane five_floor =
      GroundPlane::FromCoefficients(Eigen::Vector4d(-0.0103586, 0.997011, 0.0765573, -1.26614));
  RgbdFrame five;
  std::string error;
  if (LoadPcdFrame(dir + "/five_people.pcd", PinholeIntrinsics(), &five, &error)) {
    for (const char* hog : {"opencv", "pcl"}) for (int steps : {0, 1}) {
      DetectorOptions o;
      o.color.hog = hog;
      o.color.search_steps = steps;
      o.color.pcl_svm_file = dir + "/trainedLinearSVMForPeopleDetectionWithHOG.yaml";
      PeopleDetector d(o, five_floor, MakeHogClassifier(o.color));
      Run(std::string("five_people.pcd, colour + HOG (") + hog + ", search " + std::to_string(steps) + ")", &d,
          {five}, 30);
    }
    for (int stride : {1, 2}) {
      DetectorOptions o;
      o.color.hog = "none";
      o.pixel_stride = stride;
      PeopleDetector d(o, five_floor, nullptr);
      Run("five_people.pcd, depth only, pixel_stride " + std::to_string(stride), &d, {five}, 60);
    }
  } else {
    printf("shared data missing: %s (%s)\n", (dir + "/five_people.pcd").c_str(), error.c_str());
  }
  // Synthetic room: three people, furniture, a back wall; depth only (dark colour image).
  SyntheticScene scene;
  scene.back_wall_m = 6.5;
  scene.people = {{2.5, 0.6, 1.75, 0.5}, {3.5, -0.5, 1.65, 2.0}, {4.5, 0.8, 1.85, 3.5}};
  scene.objects = {{SyntheticObject::kChair, 2.0, -0.4, 0.3, 0},
                   {SyntheticObject::kTable, 4.0, -1.5, 0.0, 0},
                   {SyntheticObject::kCabinet, 5.5, 1.8, 0.0, 0}};
  std::vector<RgbdFrame> frames(4);
  for (int i = 0; i < 4; ++i) RenderFrame(scene, i, true, &frames[i]);
  for (int stride : {1, 2}) {
    DetectorOptions o;
    o.pixel_stride = stride;
    PeopleDetector d(o, scene.ground(), MakeOpenCvHogClassifier());
    Run("synthetic room (dark -> depth only), pixel_stride " + std::to_string(stride), &d, frames, 60);
  }
  // Including the conversion of a 16-bit depth image into the organized cloud.
  {
    const std::vector<uint16_t> depth = scene.RenderDepth(9);
    DetectorOptions o;
    o.color.hog = "none";
    PeopleDetector d(o, scene.ground(), nullptr);
    RgbdFrame f;
    const int n = 60;
    const double t0 = Now(), c0 = Cpu();
    size_t people = 0;
    for (int i = 0; i < n; ++i) {
      CloudFromDepth(depth.data(), scene.width, scene.height, 0.001, scene.intrinsics, &f);
      people += d.Detect(f).people.size();
    }
    const double dt = (Now() - t0) / n, dc = (Cpu() - c0) / n;
    printf("%-56s cpu %6.2f ms = %6.1f fps | wall %6.2f ms = %6.1f fps | %.2f people/frame\n",
           "synthetic depth image -> cloud -> detect (depth only)", 1e3 * dc, 1.0 / dc, 1e3 * dt, 1.0 / dt,
           static_cast<double>(people) / n);
  }
  return 0;
}
