// sarmap-viewer: the operator's web page, live. Subscribes to the map, pose, scan, people,
// sound sources, camera and launcher status; serves them over HTTP (read-only).
#include <cstdio>

#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/message_conversions.h"
#include "common/node.h"
#include "common/node_main.h"
#include "common/robot_config.h"
#include "sarmap/explore_status_t.hpp"
#include "viewer/viewer_options.h"
#include "viewer/viewer_server.h"

namespace {

std::string ReadToken(const std::string& path) {
  FILE* f = fopen(path.c_str(), "r");
  if (!f) throw std::runtime_error(path + ": cannot read the token file");
  char buf[256] = {0};
  const size_t n = fread(buf, 1, sizeof(buf) - 1, f);
  fclose(f);
  std::string token(buf, n);
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' '))
    token.pop_back();
  if (token.size() < 8) throw std::runtime_error(path + ": token shorter than 8 characters");
  return token;
}

}  // namespace

int main(int argc, char** argv) {
  return sarmap::common::RunMain("sarmap-viewer", [&] {
    using namespace sarmap;
    common::ArgParser parser(
        "sarmap-viewer",
        "The operator's live web page: map, robot pose and trail, scan, people (seen, heard with\n"
        "their uncertainty, both), sound sources with 3-sigma ellipses, a camera thumbnail and\n"
        "process status from the launcher. Read-only.\n"
        "In: MAP, POSE, SCAN, PEOPLE_MAP, SOUND_MAP, RGB, EXPLORE_STATUS, PM_INFO, NODE_STATUS.  "
        "Out: HTTP.");
    common::NodeArgs args;
    const auto parsed = common::ParseNodeOptions<sarmap::viewer::ViewerNodeOptions>(
        &parser, &args, argc, argv, "config/viewer.yaml");
    if (!parsed) return 0;
    const sarmap::viewer::ViewerNodeOptions& options = *parsed;
    viewer::ServerOptions server_options;
    server_options.bind_address = options.bind_address;
    server_options.port = options.port;
    if (!options.token_file.empty()) server_options.token = ReadToken(options.token_file);
    server_options.threads = options.http_threads;
    server_options.connection_limit_s = options.http_connection_limit_s;
    server_options.io_timeout_s = options.http_io_timeout_s;
    viewer::ViewerLimits limits;
    limits.forget_after_s = options.forget_after_s;
    limits.max_deputies = options.max_deputies;
    limits.max_commands_per_deputy = options.max_commands_per_deputy;
    limits.max_nodes = options.max_nodes;
    limits.max_items = options.max_items;
    limits.max_text_bytes = options.max_text_bytes;

    common::Node node("sarmap-viewer", args);
    viewer::ViewerState state(limits);
    common::Rigid2d map_from_base;

    node.Subscribe<occupancy_grid_t>(
        "MAP",
        [&](const occupancy_grid_t& m, const common::ReceiveInfo&) {
          viewer::GridImage grid;
          grid.width = m.width;
          grid.height = m.height;
          grid.resolution_m = m.resolution_m;
          grid.origin_x_m = m.origin_x_m;
          grid.origin_y_m = m.origin_y_m;
          std::string error;
          if (!common::DecodeOccupancyGrid(m, &grid.cells, &error)) {
            SARMAP_LOG(WARN) << "bad MAP: " << common::EscapeForLog(error, 512);
            return;
          }
          state.SetMap(std::move(grid));
        },
        1);
    node.Subscribe<pose_t>(
        "POSE",
        [&](const pose_t& m, const common::ReceiveInfo&) {
          map_from_base = common::ToRigid3d(m.position_m, m.orientation).ToRigid2d();
          state.SetPose(m.header.utime, map_from_base.translation().x(),
                        map_from_base.translation().y(), map_from_base.yaw_rad());
        },
        5);
    node.Subscribe<laser_scan_t>(
        "SCAN",
        [&](const laser_scan_t& m, const common::ReceiveInfo&) {
          std::vector<Eigen::Vector2d> points;
          for (int i = 0; i < m.num_ranges; ++i) {
            const double r = m.ranges_m[i];
            if (!std::isfinite(r) || r < m.range_min_m || r > m.range_max_m) continue;
            const double a = m.angle_min_rad + i * m.angle_increment_rad;
            points.push_back(map_from_base * Eigen::Vector2d(r * std::cos(a), r * std::sin(a)));
          }
          state.SetScan(std::move(points));
        },
        1);
    node.Subscribe<people_map_t>(
        "PEOPLE_MAP",
        [&](const people_map_t& m, const common::ReceiveInfo&) {
          std::vector<viewer::PersonView> people;
          for (const auto& p : m.people) {
            viewer::PersonView v;
            v.id = p.id;
            v.x_m = p.position_m[0];
            v.y_m = p.position_m[1];
            Eigen::Matrix2d cov;
            cov << p.covariance[0], p.covariance[1], p.covariance[3], p.covariance[4];
            v.ellipse = viewer::ThreeSigmaEllipse(cov);
            v.confidence = p.confidence;
            v.seen = p.cues & (mapped_person_t::CUE_SEEN_RGBD | mapped_person_t::CUE_SEEN_DEPTH);
            v.seen_depth_only = (p.cues & mapped_person_t::CUE_SEEN_DEPTH) &&
                                !(p.cues & mapped_person_t::CUE_SEEN_RGBD);
            v.heard = p.cues & mapped_person_t::CUE_HEARD;
            v.count = p.people_count;
            v.keyword = p.keyword;
            people.push_back(v);
          }
          state.SetPeople(std::move(people));
        },
        1);
    node.Subscribe<sound_map_t>(
        "SOUND_MAP",
        [&](const sound_map_t& m, const common::ReceiveInfo&) {
          std::vector<viewer::SourceView> sources;
          for (const auto& s : m.sources) {
            viewer::SourceView v;
            v.id = s.id;
            v.x_m = s.position_m[0];
            v.y_m = s.position_m[1];
            Eigen::Matrix2d cov;
            cov << s.covariance[0], s.covariance[1], s.covariance[3], s.covariance[4];
            v.ellipse = viewer::ThreeSigmaEllipse(cov);
            v.state = s.state == sound_source_t::STATE_CONVERGED ? "converged"
                      : s.state == sound_source_t::STATE_SILENT  ? "silent"
                                                                 : "initialising";
            v.is_person = s.is_person;
            static const char* kClasses[] = {"unknown", "voice", "alarm", "machinery", "music"};
            v.sound_class =
                s.sound_class >= 0 && s.sound_class <= 4 ? kClasses[s.sound_class] : "unknown";
            v.calling = s.priority == sound_source_t::PRIORITY_CALL;
            v.has_position = s.has_position;
            v.bearing_rad = s.bearing_rad;
            v.bearing_sigma_rad = std::sqrt(std::max(0.0, s.bearing_variance));
            sources.push_back(v);
          }
          state.SetSources(std::move(sources));
        },
        1);
    node.Subscribe<image_t>(
        "RGB",
        [&](const image_t& m, const common::ReceiveInfo&) {
          if (m.compression == image_t::COMPRESSION_JPEG) {
            state.SetCameraJpeg(m.data);
            return;
          }
          std::vector<uint8_t> rgb;
          std::string error;
          if (!common::DecodeColorImage(m, &rgb, &error)) return;
          state.SetCameraJpeg(common::MakeColorImage(m.header, m.intrinsics, rgb.data(), m.width,
                                                     m.height, options.camera_jpeg_quality)
                                  .data);
        },
        1);
    node.Subscribe<pm_info_t>(
        "PM_INFO",
        [&](const pm_info_t& m, const common::ReceiveInfo&) {
          static const char* kStates[] = {"stopped",  "starting", "running",
                                          "stopping", "failed",   "respawning"};
          std::vector<viewer::ProcessView> processes;
          for (const auto& c : m.commands) {
            viewer::ProcessView p;
            p.command = c.command_id;
            p.state = c.state >= 0 && c.state <= 5 ? kStates[c.state] : "?";
            p.pid = c.pid;
            p.restarts = c.restart_count;
            p.cpu_percent = c.cpu_percent;
            p.rss_mb = c.rss_bytes / 1e6;
            processes.push_back(p);
          }
          state.SetProcesses(m.deputy_id, std::move(processes), common::SteadySeconds());
        },
        20);
    node.Subscribe<node_status_t>(
        "NODE_STATUS",
        [&](const node_status_t& m, const common::ReceiveInfo&) {
          viewer::NodeView v;
          v.name = m.node_name;
          v.message = m.message;
          for (const auto& c : m.channels) v.dropped += c.dropped_malformed;
          v.last_seen_s = common::SteadySeconds();
          state.SetNode(v);
        },
        50);

    node.Subscribe<explore_status_t>(
        "EXPLORE_STATUS",
        [&](const explore_status_t& m, const common::ReceiveInfo&) {
          viewer::MissionView v;
          v.state = m.state;
          v.driven_by = m.driven_by;
          v.goal_kind = m.goal_kind;
          v.has_goal = m.has_goal;
          v.goal_x_m = m.goal_m[0];
          v.goal_y_m = m.goal_m[1];
          for (size_t i = 0; i < m.path_x_m.size() && i < m.path_y_m.size(); ++i) {
            v.path.emplace_back(m.path_x_m[i], m.path_y_m[i]);
          }
          v.frontiers = m.frontiers;
          v.recoveries = m.recoveries;
          v.stuck_s = m.stuck_s;
          v.elapsed_s = m.elapsed_s;
          state.SetMission(std::move(v));
        },
        1);

    viewer::ViewerServer server(&state, server_options);
    server.Start();
    SARMAP_LOG(INFO) << "serving http://" << options.bind_address << ":" << server.port() << "/"
                     << (server_options.token.empty() ? " (no access token)"
                                                      : " (access token required)");
    const int code = node.Run();
    server.Stop();
    return code;
  });
}
