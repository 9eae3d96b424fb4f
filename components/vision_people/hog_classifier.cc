#include "vision_people/hog_classifier.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>
#include <pcl/people/hog.h>  // non-template, light: only pcl_macros.h

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace vision_people {
namespace {

constexpr int kWinW = 64;
constexpr int kWinH = 128;

// The window around a person of `person_px` rows centred at (uc, vc), as in PCL's
// PersonClassifier::evaluate: the person is 75 % of the window height.
cv::Rect WindowRect(double uc, double vc, double person_px) {
  const int h = static_cast<int>(std::lround(person_px / 0.75));
  const int w = static_cast<int>(std::lround(person_px * 0.5 / 0.75));
  return cv::Rect(static_cast<int>(std::lround(uc - w / 2.0)),
                  static_cast<int>(std::lround(vc - h / 2.0)), w, h);
}

// Copies `rect` of `image` into a new image, black outside `image`.
cv::Mat CropWithBorder(const cv::Mat& image, const cv::Rect& rect) {
  cv::Mat out(rect.size(), image.type(), cv::Scalar::all(0));
  const cv::Rect inside = rect & cv::Rect(0, 0, image.cols, image.rows);
  if (inside.area() > 0) {
    image(inside).copyTo(out(cv::Rect(inside.x - rect.x, inside.y - rect.y, inside.width,
                                      inside.height)));
  }
  return out;
}

// Region covering the window at every shift of +-steps/8 window, resized so that the
// window is exactly kWinW x kWinH; the shifted windows then sit on an 8 x 16 px lattice.
cv::Mat SearchRegion(const cv::Mat& image, double uc, double vc, double person_px, int steps) {
  const cv::Rect win = WindowRect(uc, vc, person_px);
  const double sx = win.width / static_cast<double>(kWinW);
  const double sy = win.height / static_cast<double>(kWinH);
  const int mx = static_cast<int>(std::lround(steps * 8 * sx));
  const int my = static_cast<int>(std::lround(steps * 16 * sy));
  const cv::Rect region(win.x - mx, win.y - my, win.width + 2 * mx, win.height + 2 * my);
  cv::Mat crop = CropWithBorder(image, region);
  const cv::Size size(kWinW + 2 * 8 * steps, kWinH + 2 * 16 * steps);
  cv::Mat resized;
  cv::resize(crop, resized, size, 0, 0, crop.rows > size.height ? cv::INTER_AREA : cv::INTER_LINEAR);
  return resized;
}

std::vector<double> SearchScales(int steps) {
  if (steps <= 0) return {1.0};
  return {1.0 / 1.1, 1.0, 1.1};
}

// The best of best_window(region) over the search regions around a person (SearchRegion) at
// each of SearchScales(search_steps); -inf for a person of 4 px or less, or at no finite column.
template <class BestWindow>
double BestOverScales(const uint8_t* rgb, int width, int height, double u_center, double v_top,
                      double v_bottom, int search_steps, BestWindow& best_window) {
  const double person_px = v_bottom - v_top;
  if (!(person_px > 4) || !std::isfinite(u_center)) return -std::numeric_limits<double>::infinity();
  const cv::Mat image(height, width, CV_8UC3, const_cast<uint8_t*>(rgb));
  const double vc = 0.5 * (v_top + v_bottom);
  double best = -std::numeric_limits<double>::infinity();
  for (double scale : SearchScales(search_steps)) {
    const cv::Mat region = SearchRegion(image, u_center, vc, person_px * scale, search_steps);
    best = std::max(best, best_window(region));
  }
  return best;
}

class OpenCvHog : public HogClassifier {
 public:
  OpenCvHog() {
    hog_.winSize = cv::Size(kWinW, kWinH);
    const std::vector<float> detector = cv::HOGDescriptor::getDefaultPeopleDetector();
    weights_.assign(detector.begin(), detector.end() - 1);
    bias_ = detector.back();
  }
  std::string name() const override { return "opencv"; }

  double Score(const uint8_t* rgb, int width, int height, double u_center, double v_top,
               double v_bottom, int search_steps) const override {
    std::vector<cv::Point> locations;
    for (int j = 0; j <= 2 * search_steps; ++j) {
      for (int i = 0; i <= 2 * search_steps; ++i) locations.emplace_back(8 * i, 16 * j);
    }
    std::vector<float> descriptors;
    auto best_window = [&](const cv::Mat& region) {
      hog_.compute(region, descriptors, cv::Size(8, 8), cv::Size(0, 0), locations);
      double best = -std::numeric_limits<double>::infinity();
      const size_t n = weights_.size();
      for (size_t w = 0; w + n <= descriptors.size(); w += n) {
        double s = bias_;
        for (size_t k = 0; k < n; ++k) s += weights_[k] * descriptors[w + k];
        best = std::max(best, s);
      }
      return best;
    };
    return BestOverScales(rgb, width, height, u_center, v_top, v_bottom, search_steps, best_window);
  }

 private:
  cv::HOGDescriptor hog_;
  std::vector<float> weights_;
  double bias_ = 0;
};

// PCL's people SVM: weights over pcl::people::HOG's 3024-D descriptor of a 64x128 float
// image (column-major, channel planes, 0..1); score = w.x - b.
class PclHog : public HogClassifier {
 public:
  explicit PclHog(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read PCL HOG SVM file '" + path + "'");
    std::stringstream text;
    text << in.rdbuf();
    const std::string s = text.str();
    auto number_after = [&](const std::string& key) {
      const auto pos = s.find(key + ":");
      if (pos == std::string::npos) throw std::runtime_error(path + ": no '" + key + "'");
      return std::stod(s.substr(pos + key.size() + 1, 64));
    };
    if (number_after("window_height") != kWinH || number_after("window_width") != kWinW) {
      throw std::runtime_error(path + ": expected a 64x128 window");
    }
    bias_ = number_after("b");
    const auto open = s.find('[', s.find("weights"));
    const auto close = s.find(']', open);
    if (open == std::string::npos || close == std::string::npos) {
      throw std::runtime_error(path + ": no weights list");
    }
    std::string list = s.substr(open + 1, close - open - 1);
    std::replace(list.begin(), list.end(), ',', ' ');
    std::istringstream values(list);
    double v;
    while (values >> v) weights_.push_back(static_cast<float>(v));
    if (weights_.size() != 3024) {
      throw std::runtime_error(path + ": expected 3024 weights, found " +
                               std::to_string(weights_.size()));
    }
  }
  std::string name() const override { return "pcl"; }

  double Score(const uint8_t* rgb, int width, int height, double u_center, double v_top,
               double v_bottom, int search_steps) const override {
    std::vector<float> sample(kWinW * kWinH * 3);
    std::vector<float> descriptor(weights_.size());
    pcl::people::HOG hog;
    auto best_window = [&](const cv::Mat& region) {
      double best = -std::numeric_limits<double>::infinity();
      for (int j = 0; j <= 2 * search_steps; ++j) {
        for (int i = 0; i <= 2 * search_steps; ++i) {
          const cv::Mat win = region(cv::Rect(8 * i, 16 * j, kWinW, kWinH));
          const int plane = kWinW * kWinH;
          for (int r = 0; r < kWinH; ++r) {
            const uint8_t* row = win.ptr<uint8_t>(r);
            for (int c = 0; c < kWinW; ++c) {
              for (int ch = 0; ch < 3; ++ch) {
                sample[r + kWinH * c + plane * ch] = row[3 * c + ch] / 255.0f;
              }
            }
          }
          std::fill(descriptor.begin(), descriptor.end(), 0.0f);
          hog.compute(sample.data(), descriptor.data());
          double s = -bias_;
          for (size_t k = 0; k < weights_.size(); ++k) s += weights_[k] * descriptor[k];
          best = std::max(best, s);
        }
      }
      return best;
    };
    return BestOverScales(rgb, width, height, u_center, v_top, v_bottom, search_steps, best_window);
  }

 private:
  std::vector<float> weights_;
  double bias_ = 0;
};

}  // namespace

std::shared_ptr<const HogClassifier> MakeOpenCvHogClassifier() {
  return std::make_shared<OpenCvHog>();
}

std::shared_ptr<const HogClassifier> MakePclHogClassifier(const std::string& svm_yaml_path) {
  return std::make_shared<PclHog>(svm_yaml_path);
}

std::vector<ImageBox> DetectPeopleInImage(const uint8_t* rgb, int width, int height,
                                          const SlidingWindowOptions& options) {
  std::vector<ImageBox> out;
  if (!rgb || width <= 0 || height <= 0) return out;
  const cv::Mat image(height, width, CV_8UC3, const_cast<uint8_t*>(rgb));
  cv::Mat input = image;
  if (options.upscale != 1.0) {
    cv::resize(image, input, cv::Size(), options.upscale, options.upscale, cv::INTER_LINEAR);
  }
  const int pad_x = static_cast<int>(std::lround(options.pad_fraction * input.cols));
  const int pad_y = static_cast<int>(std::lround(options.pad_fraction * input.rows));
  if (pad_x > 0 || pad_y > 0) {
    cv::Mat padded;
    cv::copyMakeBorder(input, padded, pad_y, pad_y, pad_x, pad_x, cv::BORDER_REPLICATE);
    input = padded;
  }
  cv::HOGDescriptor hog;
  hog.setSVMDetector(cv::HOGDescriptor::getDefaultPeopleDetector());
  std::vector<cv::Rect> found;
  std::vector<double> weights;
  hog.detectMultiScale(input, found, weights, options.hit_threshold, cv::Size(8, 8),
                       cv::Size(16, 16), options.scale_step, options.group_threshold);
  for (size_t i = 0; i < found.size(); ++i) {
    ImageBox b;
    cv::Rect r = found[i];
    b.x = (r.x - pad_x) / options.upscale;
    b.y = (r.y - pad_y) / options.upscale;
    b.w = r.width / options.upscale;
    b.h = r.height / options.upscale;
    if (options.shrink_boxes) {  // as OpenCV's peopledetect sample: the window has margins
      b.x += 0.1 * b.w;
      b.w *= 0.8;
      b.y += 0.07 * b.h;
      b.h *= 0.8;
    }
    b.score = i < weights.size() ? weights[i] : 0.0;
    out.push_back(b);
  }
  return out;
}

double BoxIoU(const ImageBox& a, const ImageBox& b) {
  const double ix = std::max(0.0, std::min(a.x + a.w, b.x + b.w) - std::max(a.x, b.x));
  const double iy = std::max(0.0, std::min(a.y + a.h, b.y + b.h) - std::max(a.y, b.y));
  const double inter = ix * iy;
  const double uni = a.w * a.h + b.w * b.h - inter;
  return uni > 0 ? inter / uni : 0.0;
}

ImageBox StandardizeAspect(const ImageBox& box, double aspect) {
  ImageBox b = box;
  b.w = aspect * box.h;
  b.x = box.x + 0.5 * box.w - 0.5 * b.w;
  return b;
}

int MatchBoxes(const std::vector<ImageBox>& detections, const std::vector<ImageBox>& truth,
               double min_iou, std::vector<bool>* truth_found) {
  std::vector<size_t> order(detections.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return detections[a].score > detections[b].score; });
  std::vector<bool> used(truth.size(), false);
  int tp = 0;
  for (size_t i : order) {
    double best = min_iou;
    int best_j = -1;
    for (size_t j = 0; j < truth.size(); ++j) {
      if (used[j]) continue;
      const double iou = BoxIoU(detections[i], truth[j]);
      if (iou >= best) {
        best = iou;
        best_j = static_cast<int>(j);
      }
    }
    if (best_j >= 0) {
      used[best_j] = true;
      ++tp;
    }
  }
  if (truth_found) *truth_found = used;
  return tp;
}

std::vector<ImageBox> ReadPascalBoxes(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<ImageBox> boxes;
  const std::regex box(R"(Bounding box for object \d+ .*: \((\d+), (\d+)\) - \((\d+), (\d+)\))");
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, box)) {
      ImageBox b;
      b.x = std::stod(m[1]);
      b.y = std::stod(m[2]);
      b.w = std::stod(m[3]) - b.x;
      b.h = std::stod(m[4]) - b.y;
      boxes.push_back(b);
    }
  }
  return boxes;
}

bool ReadRgbImage(const std::string& path, std::vector<uint8_t>* rgb, int* width, int* height) {
  cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) return false;
  cv::Mat image;
  cv::cvtColor(bgr, image, cv::COLOR_BGR2RGB);
  *width = image.cols;
  *height = image.rows;
  rgb->assign(image.data, image.data + image.total() * 3);
  return true;
}

}  // namespace vision_people
}  // namespace sarmap
