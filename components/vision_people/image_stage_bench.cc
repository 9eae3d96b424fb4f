// The colour (HOG) stage side by side on the shared RGB pedestrian sets (TUD-Campus, INRIA
// samples), pinned to one core:
//   - whole-image sliding window (OpenCV's INRIA people detector) at upscale 1, 1.5 and 2:
//     precision / recall at IoU >= 0.5 on aspect-standardised boxes, CPU ms per frame;
//   - the detector's own use of the stage, scoring one window per depth candidate: every
//     annotated person (box jittered by up to 10 % of its height, as a box from depth is off)
//     against background windows of the same sizes (IoU < 0.1 with every person), per
//     classifier and window search: true / false positive rate at the decision threshold and
//     CPU ms per window.
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "vision_people/hog_classifier.h"

using namespace sarmap::vision_people;

namespace {

double Cpu() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

struct Frame {
  std::string name;
  std::vector<uint8_t> rgb;
  int width = 0, height = 0;
  std::vector<ImageBox> truth;
};

std::vector<Frame> LoadTud(const std::string& dir) {
  std::map<int, std::vector<ImageBox>> truth;
  std::ifstream gt(dir + "/gt/gt.txt");
  std::string line;
  while (std::getline(gt, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream in(line);
    int frame, id;
    ImageBox b;
    if (in >> frame >> id >> b.x >> b.y >> b.w >> b.h) truth[frame].push_back(b);
  }
  std::vector<Frame> frames;
  for (int f = 1;; ++f) {
    char name[64];
    snprintf(name, sizeof(name), "/img1/%06d.jpg", f);
    Frame frame;
    if (!ReadRgbImage(dir + name, &frame.rgb, &frame.width, &frame.height)) break;
    frame.name = name;
    frame.truth = truth[f];
    frames.push_back(std::move(frame));
  }
  return frames;
}

std::vector<Frame> LoadInria(const std::string& dir) {
  std::vector<Frame> frames;
  for (const std::string name : {"crop001501", "crop_000001"}) {
    Frame frame;
    if (!ReadRgbImage(dir + "/" + name + ".png", &frame.rgb, &frame.width, &frame.height)) continue;
    frame.name = name;
    frame.truth = ReadPascalBoxes(dir + "/" + name + ".txt");
    frames.push_back(std::move(frame));
  }
  return frames;
}

std::vector<ImageBox> Standardized(std::vector<ImageBox> boxes) {
  for (auto& b : boxes) b = StandardizeAspect(b);
  return boxes;
}

// `opencv_defaults`: detectMultiScale's own grouping (2) with neither image padding nor box
// shrinking, as OpenCV's sample calls it.
void SlidingWindow(const std::string& set, const std::vector<Frame>& frames, double upscale,
                   bool opencv_defaults = false) {
  SlidingWindowOptions options;
  options.upscale = upscale;
  if (opencv_defaults) {
    options.group_threshold = 2;
    options.pad_fraction = 0;
    options.shrink_boxes = false;
  }
  int tp = 0, detections = 0, truth = 0;
  double cpu = 0, pixels = 0;
  for (const Frame& f : frames) {
    const double c0 = Cpu();
    const auto found = DetectPeopleInImage(f.rgb.data(), f.width, f.height, options);
    cpu += Cpu() - c0;
    pixels += static_cast<double>(f.width) * f.height;
    detections += static_cast<int>(found.size());
    truth += static_cast<int>(f.truth.size());
    tp += MatchBoxes(Standardized(found), Standardized(f.truth), 0.5);
  }
  printf(
      "%-12s sliding window%s, upscale %.1f: %3d/%3d found, %3d detections: precision %.3f recall "
      "%.3f | "
      "%.0f ms per 640x480 frame (cpu)\n",
      set.c_str(), opencv_defaults ? " (OpenCV's grouping, no padding)" : "", upscale, tp, truth,
      detections, detections ? double(tp) / detections : 0.0, truth ? double(tp) / truth : 0.0,
      1e3 * cpu / pixels * 640 * 480);
}

struct Window {
  const Frame* frame;
  ImageBox box;  // the person's box (head top to feet)
  bool person;
};

// Annotated people at least 48 px tall, jittered, and as many background windows per frame.
std::vector<Window> RoiWindows(const std::vector<Frame>& frames, int negatives_per_person) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1), unit(0.0, 1.0);
  std::vector<Window> windows;
  for (const Frame& f : frames) {
    for (const ImageBox& t : f.truth) {
      if (t.h < 48) continue;
      ImageBox b = StandardizeAspect(t);
      const double scale = 1.0 + jitter(rng);
      b.x += jitter(rng) * t.h;
      b.y += jitter(rng) * t.h + 0.5 * b.h * (1 - scale);
      b.h *= scale;
      b.w *= scale;
      windows.push_back({&f, b, true});
      for (int n = 0, tries = 0; n < negatives_per_person && tries < 200; ++tries) {
        ImageBox neg = StandardizeAspect(t);
        neg.x = unit(rng) * (f.width - neg.w);
        neg.y = unit(rng) * std::max(1.0, f.height - neg.h);
        bool clear = true;
        for (const ImageBox& other : f.truth)
          clear = clear && BoxIoU(neg, StandardizeAspect(other)) < 0.1;
        if (!clear) continue;
        windows.push_back({&f, neg, false});
        ++n;
      }
    }
  }
  return windows;
}

void Roi(const std::string& set, const std::vector<Window>& windows, const HogClassifier& hog,
         double threshold, int search_steps) {
  std::vector<double> people, background;
  const double c0 = Cpu();
  for (const Window& w : windows) {
    const double s = hog.Score(w.frame->rgb.data(), w.frame->width, w.frame->height,
                               w.box.x + 0.5 * w.box.w, w.box.y, w.box.y + w.box.h, search_steps);
    (w.person ? people : background).push_back(s);
  }
  const double cpu = Cpu() - c0;
  // At the SVM threshold, and 1.6 below it: where the detector's fusion lets a candidate that
  // the depth shape fully supports through (0.6 logistic(margin) + 0.4 >= 0.5).
  auto rate = [](const std::vector<double>& v, double t) {
    return v.empty() ? 0.0 : std::count_if(v.begin(), v.end(), [t](double s) {
                               return s >= t;
                             }) / double(v.size());
  };
  printf(
      "%-12s window scoring, %-6s search_steps %d: people %3zu, background %4zu | margin >= %+.1f: "
      "people "
      "%.3f background %.3f | >= %+.1f: people %.3f background %.3f | %.2f ms per window\n",
      set.c_str(), hog.name().c_str(), search_steps, people.size(), background.size(), threshold,
      rate(people, threshold), rate(background, threshold), threshold - 1.6,
      rate(people, threshold - 1.6), rate(background, threshold - 1.6), 1e3 * cpu / windows.size());
}

}  // namespace

int main(int argc, char** argv) {
  const std::string only = argc > 1 ? argv[1] : "";  // "sliding" or "windows": one part alone
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(0, &one);
  const bool pinned = sched_setaffinity(0, sizeof(one), &one) == 0;
  printf("image stage benchmark (%s; ms = this thread's CPU time)\n",
         pinned ? "pinned to CPU 0" : "NOT pinned");
  const std::string rgb_dir = std::string(SARMAP_DATA_DIR) + "/vision/rgb";
  const auto tud = LoadTud(rgb_dir + "/tud_campus");
  const auto inria = LoadInria(rgb_dir + "/inria_samples");
  if (tud.empty() || inria.empty()) {
    printf("shared data missing: %s (tud_campus, inria_samples)\n", rgb_dir.c_str());
    return 0;
  }
  for (double upscale : {1.0, 1.5, 2.0}) {
    if (only == "windows") break;
    SlidingWindow("TUD-Campus", tud, upscale);
    SlidingWindow("INRIA", inria, upscale);
    if (upscale == 1.5) continue;
    SlidingWindow("TUD-Campus", tud, upscale, true);
    SlidingWindow("INRIA", inria, upscale, true);
  }
  if (only == "sliding") return 0;
  const auto opencv = MakeOpenCvHogClassifier();
  std::shared_ptr<const HogClassifier> pcl;
  try {
    pcl = MakePclHogClassifier(std::string(SARMAP_DATA_DIR) +
                               "/vision/pcl_people/trainedLinearSVMForPeopleDetectionWithHOG.yaml");
  } catch (const std::exception& e) {
    printf("PCL SVM not loaded: %s\n", e.what());
  }
  for (const auto& set : {std::make_pair(std::string("TUD-Campus"), &tud),
                          std::make_pair(std::string("INRIA"), &inria)}) {
    const auto windows = RoiWindows(*set.second, 3);
    for (int steps : {0, 1, 2}) {
      Roi(set.first, windows, *opencv, 0.0, steps);
      if (pcl) Roi(set.first, windows, *pcl, -1.5, steps);
    }
  }
  return 0;
}
