#include "common/message_checks.h"

#include <cmath>
#include <sstream>

namespace sarmap {
namespace common {
namespace {

// Accumulates the first failure.
class Check {
 public:
  Check& That(bool ok, const std::string& what) {
    if (!ok && error_.empty()) error_ = what;
    return *this;
  }
  Check& Finite(double v, const char* name) { return That(std::isfinite(v), std::string(name) + " not finite"); }
  template <size_t N>
  Check& Finite(const double (&v)[N], const char* name) {
    for (double x : v) Finite(x, name);
    return *this;
  }
  Check& Count(int64_t count, size_t actual, const char* name) {
    return That(count >= 0 && static_cast<size_t>(count) == actual,
                std::string(name) + " count " + std::to_string(count) + " does not match");
  }
  Check& Header(const sarmap::header_t& h) {
    That(h.utime >= 0, "negative header.utime");
    That(h.seq >= 0, "negative header.seq");
    return That(h.frame.size() < 256, "header.frame too long");
  }
  Check& UnitQuaternion(const double (&q)[4], const char* name) {
    Finite(q, name);
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    return That(std::abs(norm - 1.0) < 1e-3, std::string(name) + " is not a unit quaternion");
  }
  Check& Probability(float p, const char* name) {
    return That(std::isfinite(p) && p >= 0.f && p <= 1.f, std::string(name) + " outside [0, 1]");
  }
  const std::string& error() const { return error_; }

 private:
  std::string error_;
};

}  // namespace

std::string CheckMessage(const sarmap::audio_frame_t& m) {
  Check c;
  c.Header(m.header)
      .That(m.num_channels > 0 && m.num_channels <= 64, "num_channels outside 1..64")
      .That(m.sample_rate_hz >= 1000 && m.sample_rate_hz <= 384000, "sample_rate_hz outside 1 kHz..384 kHz")
      .That(m.num_samples >= 0, "negative num_samples")
      .That(m.sample_format == sarmap::audio_frame_t::SAMPLE_INT16, "unknown sample_format")
      .That(m.first_sample_index >= 0 && m.overrun_samples >= 0, "negative sample counter")
      .Count(m.num_values, m.samples.size(), "num_values")
      .That(static_cast<int64_t>(m.num_channels) * m.num_samples == m.num_values,
            "num_values != num_channels * num_samples");
  return c.error();
}

std::string CheckMessage(const sarmap::image_t& m) {
  Check c;
  c.Header(m.header)
      .That(m.width > 0 && m.height > 0 && m.width <= 8192 && m.height <= 8192, "bad image size")
      .That(m.pixel_format >= sarmap::image_t::PIXEL_DEPTH_U16 &&
                m.pixel_format <= sarmap::image_t::PIXEL_BGR8, "unknown pixel_format")
      .That(m.compression >= sarmap::image_t::COMPRESSION_NONE &&
                m.compression <= sarmap::image_t::COMPRESSION_PNG, "unknown compression")
      .Count(m.size, m.data.size(), "size")
      .Finite(m.depth_unit_m, "depth_unit_m")
      .That(m.pixel_format != sarmap::image_t::PIXEL_DEPTH_U16 || m.depth_unit_m > 0,
            "depth image needs depth_unit_m > 0")
      .Finite(m.intrinsics.fx, "fx").Finite(m.intrinsics.fy, "fy")
      .Finite(m.intrinsics.cx, "cx").Finite(m.intrinsics.cy, "cy");
  if (m.compression == sarmap::image_t::COMPRESSION_NONE && c.error().empty()) {
    const int bpp = m.pixel_format == sarmap::image_t::PIXEL_DEPTH_U16 ? 2
                    : m.pixel_format == sarmap::image_t::PIXEL_GRAY8   ? 1 : 3;
    c.That(static_cast<int64_t>(m.width) * m.height * bpp == m.size,
           "uncompressed size does not match width * height * bytes per pixel");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::laser_scan_t& m) {
  Check c;
  c.Header(m.header)
      .Finite(m.angle_min_rad, "angle_min_rad")
      .Finite(m.angle_increment_rad, "angle_increment_rad")
      .That(m.angle_increment_rad != 0.0, "zero angle_increment_rad")
      .That(std::isfinite(m.range_min_m) && std::isfinite(m.range_max_m) && m.range_min_m >= 0 &&
                m.range_max_m > m.range_min_m, "bad range limits")
      .Count(m.num_ranges, m.ranges_m.size(), "num_ranges")
      .Count(m.num_intensities, m.intensities.size(), "num_intensities")
      .That(m.num_intensities == 0 || m.num_intensities == m.num_ranges,
            "num_intensities must be 0 or num_ranges")
      .That(std::abs(m.angle_increment_rad * m.num_ranges) <= 2 * M_PI + 1e-6,
            "scan spans more than a full turn");
  return c.error();
}

std::string CheckMessage(const sarmap::pose_t& m) {
  Check c;
  c.Header(m.header).Finite(m.position_m, "position_m").UnitQuaternion(m.orientation, "orientation")
      .Finite(m.covariance, "covariance");
  return c.error();
}

std::string CheckMessage(const sarmap::odometry_t& m) {
  Check c;
  c.Header(m.header).Finite(m.position_m, "position_m").UnitQuaternion(m.orientation, "orientation")
      .Finite(m.pose_covariance, "pose_covariance")
      .Finite(m.linear_velocity_mps, "linear_velocity_mps")
      .Finite(m.angular_velocity_radps, "angular_velocity_radps")
      .Finite(m.twist_covariance, "twist_covariance");
  return c.error();
}

std::string CheckMessage(const sarmap::occupancy_grid_t& m) {
  Check c;
  c.Header(m.header)
      .That(std::isfinite(m.resolution_m) && m.resolution_m > 0, "resolution_m must be > 0")
      .That(m.width > 0 && m.height > 0 && static_cast<int64_t>(m.width) * m.height <= (1 << 28),
            "bad grid size")
      .Finite(m.origin_x_m, "origin_x_m").Finite(m.origin_y_m, "origin_y_m")
      .Finite(m.origin_yaw_rad, "origin_yaw_rad")
      .That(m.compression == sarmap::occupancy_grid_t::COMPRESSION_NONE ||
                m.compression == sarmap::occupancy_grid_t::COMPRESSION_ZSTD, "unknown compression")
      .Count(m.size, m.data.size(), "size");
  if (m.compression == sarmap::occupancy_grid_t::COMPRESSION_NONE && c.error().empty()) {
    c.That(static_cast<int64_t>(m.width) * m.height == m.size, "size != width * height");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::slam_anchor_request_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_node_ids, m.node_ids.size(), "num_node_ids")
      .That(!m.client_id.empty(), "empty client_id");
  return c.error();
}

std::string CheckMessage(const sarmap::slam_anchors_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_anchors, m.anchors.size(), "num_anchors")
      .Count(m.covariance_dim, m.covariance.size(), "covariance_dim")
      .That(m.covariance_dim == 3 * (1 + m.num_anchors), "covariance_dim != 3 * (1 + num_anchors)");
  for (const auto& row : m.covariance) {
    c.That(row.size() == m.covariance.size(), "covariance not square");
    for (double v : row) c.Finite(v, "covariance");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::doa_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_sources, m.sources.size(), "num_sources");
  for (const auto& s : m.sources) {
    c.That(s.kind >= sarmap::doa_source_t::KIND_ANGLE_1D &&
               s.kind <= sarmap::doa_source_t::KIND_AZIMUTH_ELEVATION,
           "unknown DOA kind")
        .That(s.method >= sarmap::doa_source_t::METHOD_GCC_PHAT &&
                  s.method <= sarmap::doa_source_t::METHOD_ESPRIT,
              "unknown DOA method")
        .Finite(s.azimuth_rad, "azimuth_rad")
        .Finite(s.elevation_rad, "elevation_rad")
        .Finite(s.covariance, "covariance")
        .Probability(s.confidence, "confidence")
        .That(s.sound_class >= sarmap::doa_source_t::SOUND_CLASS_UNKNOWN &&
                  s.sound_class <= sarmap::doa_source_t::SOUND_CLASS_MUSIC,
              "unknown sound_class")
        .Probability(s.class_confidence, "class_confidence");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::speech_event_t& m) {
  Check c;
  c.Header(m.header).Probability(m.confidence, "confidence")
      .Finite(m.azimuth_rad, "azimuth_rad").Finite(m.elevation_rad, "elevation_rad")
      .That(m.end_utime >= m.start_utime, "end_utime before start_utime");
  return c.error();
}

std::string CheckMessage(const sarmap::people_detections_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_detections, m.detections.size(), "num_detections");
  for (const auto& d : m.detections) {
    c.That(d.cue >= sarmap::person_detection_t::CUE_SEEN_RGBD &&
               d.cue <= sarmap::person_detection_t::CUE_HEARD, "unknown cue")
        .Finite(d.azimuth_rad, "azimuth_rad").Finite(d.elevation_rad, "elevation_rad")
        .Finite(d.direction_covariance, "direction_covariance")
        .Probability(d.confidence, "confidence");
    if (d.has_range) c.Finite(d.position_m, "position_m").Finite(d.position_covariance, "position_covariance");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::people_map_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_people, m.people.size(), "num_people");
  for (const auto& p : m.people) {
    c.Finite(p.position_m, "position_m").Finite(p.covariance, "covariance")
        .Probability(p.confidence, "confidence").That(p.num_detections >= 0, "negative num_detections");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::sound_map_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_sources, m.sources.size(), "num_sources");
  for (const auto& s : m.sources) {
    c.Finite(s.position_m, "position_m")
        .Finite(s.covariance, "covariance")
        .That(s.state >= sarmap::sound_source_t::STATE_INITIALISING &&
                  s.state <= sarmap::sound_source_t::STATE_SILENT,
              "unknown state")
        .Finite(s.bearing_origin_m, "bearing_origin_m")
        .That(std::isfinite(s.bearing_rad) && std::isfinite(s.bearing_variance),
              "non-finite bearing")
        .That(s.sound_class >= 0 && s.sound_class <= 4, "unknown sound_class")
        .Probability(s.class_confidence, "class_confidence");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::velocity_command_t& m) {
  Check c;
  c.Header(m.header).Finite(m.linear_mps, "linear_mps").Finite(m.angular_radps, "angular_radps");
  return c.error();
}

std::string CheckMessage(const sarmap::teleop_t& m) {
  Check c;
  c.Header(m.header).Finite(m.linear_mps, "linear_mps").Finite(m.angular_radps, "angular_radps");
  return c.error();
}

std::string CheckMessage(const sarmap::sim_truth_t& m) {
  Check c;
  c.Header(m.header).Finite(m.robot_position_m, "robot_position_m")
      .UnitQuaternion(m.robot_orientation, "robot_orientation")
      .Count(m.num_people, m.people.size(), "num_people")
      .Count(m.num_sources, m.sources.size(), "num_sources");
  for (const auto& p : m.people) c.Finite(p.position_m, "people.position_m");
  for (const auto& s : m.sources) c.Finite(s.position_m, "sources.position_m");
  c.Finite(m.start_pose, "start_pose").Finite(m.distance_m, "distance_m")
      .That(m.collisions >= 0, "collisions negative");
  return c.error();
}

std::string CheckMessage(const sarmap::explore_status_t& m) {
  Check c;
  c.Header(m.header).Finite(m.goal_m, "goal_m")
      .Count(m.num_path, m.path_x_m.size(), "num_path")
      .Count(m.num_path, m.path_y_m.size(), "num_path")
      .Finite(m.stuck_s, "stuck_s").Finite(m.elapsed_s, "elapsed_s");
  for (size_t i = 0; i < m.path_x_m.size() && i < m.path_y_m.size(); ++i) {
    c.Finite(m.path_x_m[i], "path_x_m").Finite(m.path_y_m[i], "path_y_m");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::node_status_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_channels, m.channels.size(), "num_channels");
  return c.error();
}

std::string CheckMessage(const sarmap::pm_orders_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_commands, m.commands.size(), "num_commands")
      .That(m.counter >= 0, "negative counter");
  for (const auto& cmd : m.commands) {
    c.That(!cmd.command_id.empty(), "empty command_id")
        .That(cmd.stop_signal > 0 && cmd.stop_signal < 65, "bad stop_signal")
        .That(std::isfinite(cmd.stop_time_allowed_s) && cmd.stop_time_allowed_s >= 0,
              "bad stop_time_allowed_s");
  }
  return c.error();
}

std::string CheckMessage(const sarmap::pm_info_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_commands, m.commands.size(), "num_commands");
  return c.error();
}

std::string CheckMessage(const sarmap::pm_output_t& m) {
  Check c;
  c.Header(m.header).Count(m.num_commands, m.command_ids.size(), "num_commands")
      .Count(m.num_commands, m.text.size(), "num_commands");
  return c.error();
}

}  // namespace common
}  // namespace sarmap
