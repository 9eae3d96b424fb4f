#include "vision_people/image_frame.h"

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace sarmap {
namespace vision_people {

std::string FindColorImage(const std::string& depth_path) {
  const size_t slash = depth_path.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : depth_path.substr(0, slash + 1);
  const std::string name = depth_path.substr(dir.size());
  std::vector<std::string> candidates;
  auto replaced = [](std::string s, const std::string& from, const std::string& to) {
    const size_t at = s.rfind(from);
    if (at == std::string::npos) return std::string();
    return s.replace(at, from.size(), to);
  };
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"depth", "color"},
                                 {"depth", "rgb"},
                                 {"depth", "image"},
                                 {"dep_", "img_"}}) {
    const std::string p = replaced(depth_path, from, to);
    if (p.empty()) continue;
    candidates.push_back(p);
    const size_t dot = p.rfind('.');
    if (dot != std::string::npos && dot > p.rfind('/'))
      candidates.push_back(p.substr(0, dot) + ".png");
  }
  for (const std::string& p : candidates) {
    if (p != depth_path && access(p.c_str(), R_OK) == 0) return p;
  }
  return "";
}

bool LoadDepthImageFrame(const std::string& depth_path, const std::string& color_path,
                         double unit_m, const PinholeIntrinsics& intrinsics, RgbdFrame* frame,
                         std::string* error) {
  const cv::Mat d = cv::imread(depth_path, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
  if (d.empty()) {
    *error = "cannot read depth image '" + depth_path + "'";
    return false;
  }
  if (d.type() != CV_16UC1) {
    *error = depth_path + ": depth must be a 16-bit single-channel image (this one is " +
             (d.depth() == CV_8U ? std::string("8-bit: its range is lost")
                                 : "of OpenCV type " + std::to_string(d.type())) +
             ")";
    return false;
  }
  const cv::Mat dc = d.isContinuous() ? d : d.clone();
  CloudFromDepth(dc.ptr<uint16_t>(), dc.cols, dc.rows, unit_m, intrinsics, frame);
  frame->rgb.clear();
  if (color_path.empty()) return true;
  cv::Mat c = cv::imread(color_path, cv::IMREAD_COLOR);
  if (c.empty()) {
    *error = "cannot read colour image '" + color_path + "'";
    return false;
  }
  if (c.cols != dc.cols || c.rows != dc.rows) {
    *error = color_path + ": colour " + std::to_string(c.cols) + "x" + std::to_string(c.rows) +
             " does not match the depth " + std::to_string(dc.cols) + "x" + std::to_string(dc.rows);
    return false;
  }
  cv::cvtColor(c, c, cv::COLOR_BGR2RGB);
  if (!c.isContinuous()) c = c.clone();
  frame->rgb.assign(c.data, c.data + c.total() * 3);
  return true;
}

}  // namespace vision_people
}  // namespace sarmap
