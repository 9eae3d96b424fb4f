#include "log-tools/geotiff.h"

#include <cpl_conv.h>
#include <cpl_string.h>
#include <gdal.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/image_messages.h"

namespace sarmap {
namespace logtools {

namespace {

cv::Scalar Rgb(const std::array<uint8_t, 3>& c) { return cv::Scalar(c[0], c[1], c[2]); }

// Map frame -> pixel (fractional column and row of the image, row 0 at the top).
struct PixelFrame {
  double x0, y0, c, s, resolution;
  int height;
  cv::Point2d Pixel(double x, double y) const {
    const double dx = x - x0, dy = y - y0;
    const double u = c * dx + s * dy, v = -s * dx + c * dy;  // in the grid's frame
    return cv::Point2d(u / resolution, height - v / resolution);
  }
  cv::Point P(double x, double y) const {
    const cv::Point2d p = Pixel(x, y);
    return cv::Point(static_cast<int>(std::floor(p.x)), static_cast<int>(std::floor(p.y)));
  }
};

void Ellipse(cv::Mat* image, const PixelFrame& f, double x, double y, const double* cov,
             const cv::Scalar& colour) {
  Eigen::Matrix2d P;
  P << cov[0], cov[1], cov[3], cov[4];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (P + P.transpose()));
  const Eigen::Vector2d v = eig.eigenvalues().cwiseMax(0.0);
  const Eigen::Vector2d axis = eig.eigenvectors().col(1);
  // Image rows grow downwards and the grid may be turned: the angle in pixels.
  const double angle_deg = -(std::atan2(axis.y(), axis.x()) - std::atan2(f.s, f.c)) * 180 / M_PI;
  const double max_px = 4.0 * std::max(image->cols, image->rows);
  const auto px = [&](double variance) {
    return std::max(1, static_cast<int>(std::min(max_px, 3 * std::sqrt(variance) / f.resolution)));
  };
  cv::ellipse(*image, f.P(x, y), cv::Size(px(v(1)), px(v(0))), angle_deg, 0, 360, colour, 1,
              cv::LINE_8);
}

}  // namespace

constexpr std::array<uint8_t, 3> GeoTiffColours::kFree, GeoTiffColours::kOccupied,
    GeoTiffColours::kUnknownA, GeoTiffColours::kUnknownB, GeoTiffColours::kGrid,
    GeoTiffColours::kPath, GeoTiffColours::kStart, GeoTiffColours::kSeen, GeoTiffColours::kHeard,
    GeoTiffColours::kSeenAndHeard, GeoTiffColours::kSoundSource;

std::array<uint8_t, 3> PersonColour(int cues) {
  const bool heard = cues & sarmap::mapped_person_t::CUE_HEARD;
  const bool seen =
      cues & (sarmap::mapped_person_t::CUE_SEEN_RGBD | sarmap::mapped_person_t::CUE_SEEN_DEPTH);
  return seen && heard ? GeoTiffColours::kSeenAndHeard
         : heard       ? GeoTiffColours::kHeard
                       : GeoTiffColours::kSeen;
}

std::array<double, 6> MapGeoTransform(const sarmap::occupancy_grid_t& m) {
  const double c = std::cos(m.origin_yaw_rad), s = std::sin(m.origin_yaw_rad), r = m.resolution_m;
  const double top = m.height * r;  // row 0 of the image is the grid's last row
  return {m.origin_x_m - s * top, c * r, s * r, m.origin_y_m + c * top, s * r, -c * r};
}

void WriteGeoTiff(const MissionData& data, const MissionSummary& summary, const std::string& path) {
  if (!data.map) throw std::runtime_error("no map (MAP) in " + data.log_path + ": no GeoTIFF");
  const auto& m = *data.map;
  std::vector<int8_t> cells;
  std::string error;
  if (!common::DecodeOccupancyGrid(m, &cells, &error) || m.width <= 0 || m.height <= 0 ||
      !(m.resolution_m > 0)) {
    throw std::runtime_error("the map cannot be drawn: " + (error.empty() ? "empty grid" : error));
  }
  const int w = m.width, h = m.height;
  const double res = m.resolution_m;
  const PixelFrame f{
      m.origin_x_m, m.origin_y_m, std::cos(m.origin_yaw_rad), std::sin(m.origin_yaw_rad), res, h};
  cv::Mat image(h, w, CV_8UC3);  // RGB
  // Cells: unknown as a 1 m checkerboard, free white, obstacles dark blue; 1 m grid lines over
  // the free and unknown cells (in the grid's frame, whose origin is on a whole metre or not).
  const auto metre = [&](int i) { return static_cast<int64_t>(std::floor((i * res) + 1e-9)); };
  for (int row = 0; row < h; ++row) {
    const int gy = h - 1 - row;
    const bool grid_row = metre(gy) != metre(gy + 1);
    for (int col = 0; col < w; ++col) {
      const int8_t v = cells[static_cast<size_t>(gy) * w + col];
      std::array<uint8_t, 3> colour;
      if (v >= 65) {
        colour = GeoTiffColours::kOccupied;
      } else if (grid_row || metre(col) != metre(col + 1)) {
        colour = GeoTiffColours::kGrid;
      } else if (v < 0) {
        colour = ((metre(col) + metre(gy)) % 2 == 0) ? GeoTiffColours::kUnknownA
                                                     : GeoTiffColours::kUnknownB;
      } else if (v < 50) {  // more likely free than occupied
        colour = GeoTiffColours::kFree;
      } else {  // uncertain: between free and occupied
        colour = {160, 170, 195};
      }
      image.at<cv::Vec3b>(row, col) = cv::Vec3b(colour[0], colour[1], colour[2]);
    }
  }
  const int thickness = std::max(1, static_cast<int>(std::lround(0.05 / res)));
  for (size_t i = 1; i < data.trail.size(); ++i) {
    cv::line(image, f.P(data.trail[i - 1].first, data.trail[i - 1].second),
             f.P(data.trail[i].first, data.trail[i].second), Rgb(GeoTiffColours::kPath), thickness,
             cv::LINE_8);
  }
  if (data.has_start) {  // an arrow 0.6 m long along the start heading
    const double x = data.start_x_m, y = data.start_y_m, yaw = data.start_yaw_rad;
    cv::arrowedLine(image, f.P(x, y), f.P(x + 0.6 * std::cos(yaw), y + 0.6 * std::sin(yaw)),
                    Rgb(GeoTiffColours::kStart), std::max(1, 2 * thickness), cv::LINE_8, 0, 0.35);
  }
  // Sound sources: a filled square with its 3-sigma ellipse once converged; a hollow square
  // alone while initialising (its ellipse can span the whole map).
  for (const auto& s : SourcesOnMap(data, summary)) {
    const bool converged = s.state == sarmap::sound_source_t::STATE_CONVERGED;
    if (converged)
      Ellipse(&image, f, s.position_m[0], s.position_m[1], s.covariance,
              Rgb(GeoTiffColours::kSoundSource));
    const int half = std::max(2, static_cast<int>(0.1 / res));
    const cv::Point p = f.P(s.position_m[0], s.position_m[1]);
    cv::rectangle(image, p - cv::Point(half, half), p + cv::Point(half, half),
                  Rgb(GeoTiffColours::kSoundSource), converged ? cv::FILLED : 1);
  }
  const int radius = std::max(3, static_cast<int>(std::lround(0.2 / res)));
  for (const auto& p : PeopleOnMap(data, summary)) {
    const cv::Scalar colour = Rgb(PersonColour(p.cues));
    Ellipse(&image, f, p.position_m[0], p.position_m[1], p.covariance, colour);
    const cv::Point at = f.P(p.position_m[0], p.position_m[1]);
    cv::circle(image, at, radius, colour, cv::FILLED, cv::LINE_8);
    cv::putText(image, std::to_string(p.id), at + cv::Point(radius + 2, -radius),
                cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }

  GDALAllRegister();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  if (!driver) throw std::runtime_error("GDAL has no GTiff driver");
  char** create_options = nullptr;
  create_options = CSLSetNameValue(create_options, "COMPRESS", "DEFLATE");
  create_options = CSLSetNameValue(create_options, "PHOTOMETRIC", "RGB");
  GDALDatasetH ds = GDALCreate(driver, path.c_str(), w, h, 3, GDT_Byte, create_options);
  CSLDestroy(create_options);
  if (!ds) throw std::runtime_error("cannot write GeoTIFF '" + path + "': " + CPLGetLastErrorMsg());
  std::array<double, 6> g = MapGeoTransform(m);
  GDALSetGeoTransform(ds, g.data());
  GDALSetProjection(
      ds,
      "LOCAL_CS[\"sarmap map frame\",LOCAL_DATUM[\"sarmap map frame\",32767],"
      "UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"X\",EAST],AXIS[\"Y\",NORTH]]");
  GDALSetMetadataItem(ds, "TIFFTAG_SOFTWARE", "sarmap-log geotiff", nullptr);
  GDALSetMetadataItem(
      ds, "TIFFTAG_IMAGEDESCRIPTION",
      "sarmap mission map (RoboCup Rescue style): white free, dark blue obstacles, grey "
      "checkerboard unknown (1 m), 1 m grid, orange robot path, green arrow start pose, "
      "people red seen / magenta heard / yellow seen+heard with 3-sigma ellipses, blue sound "
      "sources",
      nullptr);
  std::vector<uint8_t> band(static_cast<size_t>(w) * h);
  CPLErr err = CE_None;
  for (int b = 0; b < 3 && err == CE_None; ++b) {
    for (int row = 0; row < h; ++row) {
      const cv::Vec3b* px = image.ptr<cv::Vec3b>(row);
      for (int col = 0; col < w; ++col) band[static_cast<size_t>(row) * w + col] = px[col][b];
    }
    GDALRasterBandH rb = GDALGetRasterBand(ds, b + 1);
    GDALSetRasterColorInterpretation(rb, b == 0   ? GCI_RedBand
                                         : b == 1 ? GCI_GreenBand
                                                  : GCI_BlueBand);
    err = GDALRasterIO(rb, GF_Write, 0, 0, w, h, band.data(), w, h, GDT_Byte, 0, 0);
  }
  GDALClose(ds);
  if (err != CE_None)
    throw std::runtime_error("cannot write GeoTIFF '" + path + "': " + CPLGetLastErrorMsg());
}

}  // namespace logtools
}  // namespace sarmap
