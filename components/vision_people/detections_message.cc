#include "vision_people/detections_message.h"

#include <algorithm>
#include <cmath>

#include "common/message_conversions.h"

namespace sarmap {
namespace vision_people {

void FillDirection(const Eigen::Vector3d& p, const Eigen::Matrix3d& cov,
                   sarmap::person_detection_t* out) {
  const double x = p.x(), y = p.y(), z = p.z();
  const double rho2 = x * x + z * z, rho = std::sqrt(rho2), r2 = rho2 + y * y;
  out->azimuth_rad = std::atan2(-x, z);
  out->elevation_rad = std::atan2(-y, rho);
  Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Zero();
  if (rho2 > 1e-12 && r2 > 1e-12) {
    J << -z / rho2, 0, x / rho2,                            // d atan2(-x, z)
        y * x / (rho * r2), -rho / r2, y * z / (rho * r2);  // d atan2(-y, rho)
  }
  const Eigen::Matrix2d dcov = J * cov * J.transpose();
  for (int i = 0; i < 4; ++i) out->direction_covariance[i] = dcov(i / 2, i % 2);
}

sarmap::people_detections_t DetectionsMessage(const std::vector<ConfirmedPerson>& confirmed,
                                              int64_t utime, const std::string& sensor_id) {
  sarmap::people_detections_t msg;
  msg.header.utime = utime;
  msg.header.frame = "camera";
  msg.sensor_id = sensor_id;
  for (const auto& c : confirmed) {
    sarmap::person_detection_t d{};
    d.track_id = c.track_id;
    d.cue = c.person.hog_used ? sarmap::person_detection_t::CUE_SEEN_RGBD
                              : sarmap::person_detection_t::CUE_SEEN_DEPTH;
    d.has_range = true;
    for (int i = 0; i < 3; ++i) d.position_m[i] = c.person.position_camera(i);
    common::FromCovariance3(c.person.covariance, d.position_covariance);
    FillDirection(c.person.position_camera, c.person.covariance, &d);
    d.height_m = static_cast<float>(c.person.height_m);
    d.confidence = static_cast<float>(std::clamp(c.person.confidence, 0.0, 1.0));
    d.keyword = "";
    msg.detections.push_back(d);
  }
  msg.num_detections = static_cast<int32_t>(msg.detections.size());
  return msg;
}

}  // namespace vision_people
}  // namespace sarmap
