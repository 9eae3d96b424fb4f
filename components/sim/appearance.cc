#include "sim/appearance.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

namespace sarmap {
namespace sim {
namespace {

// The person fills this fraction of the crop's height: HOG's 64x128 window holds a ~96 px
// tall person, i.e. a 16 px margin above and below.
constexpr double kPersonFraction = 0.75;

bool Crop(const cv::Mat& bgr, const cv::Rect2d& box, const std::string& origin, Appearance* out) {
  const double crop_h = box.height / kPersonFraction;
  const double crop_w = crop_h / 2.0;
  const double cx = box.x + box.width / 2, top = box.y - (crop_h - box.height) / 2;
  cv::Rect roi(static_cast<int>(std::lround(cx - crop_w / 2)), static_cast<int>(std::lround(top)),
               static_cast<int>(std::lround(crop_w)), static_cast<int>(std::lround(crop_h)));
  if (roi.width < 16 || roi.height < 32) return false;
  // Pad by replicating the border where the crop leaves the photo.
  const int pad = std::max({0, -roi.x, -roi.y, roi.x + roi.width - bgr.cols, roi.y + roi.height - bgr.rows});
  cv::Mat padded;
  cv::copyMakeBorder(bgr, padded, pad, pad, pad, pad, cv::BORDER_REPLICATE);
  cv::Mat crop = padded(cv::Rect(roi.x + pad, roi.y + pad, roi.width, roi.height)).clone();
  cv::Mat rgb;
  cv::cvtColor(crop, rgb, cv::COLOR_BGR2RGB);
  out->origin = origin;
  out->width = rgb.cols;
  out->height = rgb.rows;
  out->rgb.resize(static_cast<size_t>(rgb.cols) * rgb.rows * 3);
  for (int y = 0; y < rgb.rows; ++y) {
    const uint8_t* row = rgb.ptr<uint8_t>(y);
    for (int x = 0; x < rgb.cols * 3; ++x) out->rgb[static_cast<size_t>(y) * rgb.cols * 3 + x] = row[x];
  }
  out->person_top = (box.y - top) / crop_h;
  out->person_bottom = (box.y + box.height - top) / crop_h;
  return true;
}

// INRIA PASCAL annotation: "Bounding box for object N ... : (x1, y1) - (x2, y2)".
std::vector<cv::Rect2d> InriaBoxes(const std::string& txt) {
  std::ifstream in(txt);
  std::vector<cv::Rect2d> boxes;
  std::string line;
  const std::regex re(R"(Bounding box.*:\s*\((\d+),\s*(\d+)\)\s*-\s*\((\d+),\s*(\d+)\))");
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_search(line, m, re)) {
      const double x1 = std::stod(m[1]), y1 = std::stod(m[2]), x2 = std::stod(m[3]), y2 = std::stod(m[4]);
      boxes.emplace_back(x1, y1, x2 - x1, y2 - y1);
    }
  }
  return boxes;
}

}  // namespace

std::vector<Appearance> LoadAppearances(const std::string& data_dir, int max_count,
                                        std::string* warning) {
  std::vector<Appearance> out;
  const std::string tud = data_dir + "/vision/rgb/tud_campus";
  // TUD-Campus: per track, the tallest unclipped box whose crop holds no other person
  // (a crop showing two people would be two detections).
  std::ifstream gt(tud + "/gt/gt.txt");
  if (gt) {
    struct Box {
      int frame, id;
      cv::Rect2d box;
    };
    std::vector<Box> boxes;
    std::map<int, std::vector<cv::Rect2d>> by_frame;
    std::string line;
    while (std::getline(gt, line)) {
      int frame = 0, id = 0;
      double x = 0, y = 0, w = 0, h = 0;
      if (std::sscanf(line.c_str(), "%d,%d,%lf,%lf,%lf,%lf", &frame, &id, &x, &y, &w, &h) != 6) continue;
      by_frame[frame].emplace_back(x, y, w, h);
      if (x < 2 || y < 2 || x + w > 638 || y + h > 478 || h < 200) continue;  // big, sharp crops
      boxes.push_back({frame, id, cv::Rect2d(x, y, w, h)});
    }
    std::stable_sort(boxes.begin(), boxes.end(),
                     [](const Box& a, const Box& b) { return a.box.height > b.box.height; });
    std::set<int> used_tracks;
    for (const Box& b : boxes) {
      if (static_cast<int>(out.size()) >= max_count) break;
      if (used_tracks.count(b.id)) continue;
      const double crop_h = b.box.height / kPersonFraction;
      const cv::Rect2d crop(b.box.x + b.box.width / 2 - crop_h / 4, b.box.y - (crop_h - b.box.height) / 2,
                            crop_h / 2, crop_h);
      bool alone = true;
      for (const cv::Rect2d& other : by_frame[b.frame]) {
        if (other == b.box) continue;
        alone = alone && (other & crop).area() < 0.1 * other.area();
      }
      if (!alone) continue;
      char name[32];
      std::snprintf(name, sizeof(name), "/img1/%06d.jpg", b.frame);
      const cv::Mat img = cv::imread(tud + name, cv::IMREAD_COLOR);
      if (img.empty()) continue;
      Appearance a;
      if (Crop(img, b.box, "tud_campus" + std::string(name) + " track " + std::to_string(b.id), &a)) {
        out.push_back(std::move(a));
        used_tracks.insert(b.id);
      }
    }
  }
  for (const char* stem : {"crop001501", "crop_000001"}) {
    if (static_cast<int>(out.size()) >= max_count) break;
    const std::string base = data_dir + "/vision/rgb/inria_samples/" + stem;
    if (!std::ifstream(base + ".png").good()) continue;  // quietly: the warning below says it all
    const cv::Mat img = cv::imread(base + ".png", cv::IMREAD_COLOR);
    if (img.empty()) continue;
    for (const cv::Rect2d& box : InriaBoxes(base + ".txt")) {
      if (static_cast<int>(out.size()) >= max_count) break;
      Appearance a;
      if (box.height >= 100 && Crop(img, box, std::string("inria ") + stem, &a)) out.push_back(std::move(a));
    }
  }
  if (out.empty()) {
    *warning = "no people photos under " + data_dir +
               "/vision/rgb (tud_campus, inria_samples): people are drawn figures, which a HOG "
               "detector will not recognise";
    for (int i = 0; i < std::max(1, max_count); ++i) out.push_back(DrawnFigure(i));
  }
  return out;
}

Appearance DrawnFigure(int variant) {
  const int w = 64, h = 128;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(150, 150, 150));
  const cv::Scalar shirt = variant % 2 ? cv::Scalar(40, 40, 160) : cv::Scalar(160, 60, 30);
  const cv::Scalar trousers(50, 40, 30), skin(120, 160, 210);
  cv::circle(img, cv::Point(32, 26), 9, skin, cv::FILLED, cv::LINE_AA);
  cv::rectangle(img, cv::Rect(21, 36, 22, 34), shirt, cv::FILLED);
  cv::rectangle(img, cv::Rect(15, 38, 6, 28), shirt, cv::FILLED);
  cv::rectangle(img, cv::Rect(43, 38, 6, 28), shirt, cv::FILLED);
  cv::rectangle(img, cv::Rect(22, 70, 9, 42), trousers, cv::FILLED);
  cv::rectangle(img, cv::Rect(33, 70, 9, 42), trousers, cv::FILLED);
  Appearance a;
  Crop(img, cv::Rect2d(15, 16, 34, 96), "drawn figure " + std::to_string(variant), &a);
  return a;
}

}  // namespace sim
}  // namespace sarmap
