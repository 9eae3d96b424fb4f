#include "common/image_codec.h"

#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace sarmap {
namespace common {

sarmap::image_t MakeColorImage(const sarmap::header_t& header,
                               const sarmap::camera_intrinsics_t& intrinsics, const uint8_t* rgb,
                               int width, int height, int jpeg_quality) {
  sarmap::image_t image;
  image.header = header;
  image.intrinsics = intrinsics;
  image.width = width;
  image.height = height;
  image.pixel_format = sarmap::image_t::PIXEL_RGB8;
  image.depth_unit_m = 0.0;
  const size_t n = static_cast<size_t>(width) * height * 3;
  if (jpeg_quality > 0) {
    // OpenCV encodes BGR; swap channels into a temporary.
    cv::Mat bgr;
    cv::cvtColor(cv::Mat(height, width, CV_8UC3, const_cast<uint8_t*>(rgb)), bgr, cv::COLOR_RGB2BGR);
    cv::imencode(".jpg", bgr, image.data, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
    image.compression = sarmap::image_t::COMPRESSION_JPEG;
  } else {
    image.data.assign(rgb, rgb + n);
    image.compression = sarmap::image_t::COMPRESSION_NONE;
  }
  image.size = static_cast<int32_t>(image.data.size());
  return image;
}

bool DecodeColorImage(const sarmap::image_t& image, std::vector<uint8_t>* rgb, std::string* error) {
  const int w = image.width, h = image.height;
  if (w <= 0 || h <= 0 || image.data.size() != static_cast<size_t>(image.size)) {
    *error = "bad colour image header";
    return false;
  }
  rgb->resize(static_cast<size_t>(w) * h * 3);
  cv::Mat out(h, w, CV_8UC3, rgb->data());
  if (image.compression == sarmap::image_t::COMPRESSION_NONE) {
    const int channels = image.pixel_format == sarmap::image_t::PIXEL_GRAY8 ? 1 : 3;
    if (image.pixel_format == sarmap::image_t::PIXEL_DEPTH_U16 ||
        image.data.size() != static_cast<size_t>(w) * h * channels) {
      *error = "raw colour image of wrong size or format";
      return false;
    }
    cv::Mat in(h, w, channels == 1 ? CV_8UC1 : CV_8UC3, const_cast<uint8_t*>(image.data.data()));
    if (image.pixel_format == sarmap::image_t::PIXEL_RGB8) in.copyTo(out);
    else if (image.pixel_format == sarmap::image_t::PIXEL_BGR8) cv::cvtColor(in, out, cv::COLOR_BGR2RGB);
    else cv::cvtColor(in, out, cv::COLOR_GRAY2RGB);
    return true;
  }
  if (image.compression != sarmap::image_t::COMPRESSION_JPEG &&
      image.compression != sarmap::image_t::COMPRESSION_PNG) {
    *error = "unsupported colour compression " + std::to_string(image.compression);
    return false;
  }
  cv::Mat decoded;
  try {
    decoded = cv::imdecode(image.data, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    decoded.release();
  }
  if (decoded.empty()) {
    *error = "corrupt compressed colour image";
    return false;
  }
  if (decoded.cols != w || decoded.rows != h) {
    *error = "decoded colour image is " + std::to_string(decoded.cols) + "x" +
             std::to_string(decoded.rows) + ", header says " + std::to_string(w) + "x" +
             std::to_string(h);
    return false;
  }
  cv::cvtColor(decoded, out, cv::COLOR_BGR2RGB);
  return true;
}

}  // namespace common
}  // namespace sarmap
