#include "viewer/viewer_node.h"

#include <cstdio>
#include <stdexcept>
#include <string>

#include "common/grid_geometry.h"
#include "common/image_codec.h"
#include "common/image_messages.h"
#include "common/logging.h"
#include "common/message_conversions.h"
#include "viewer/viewer_messages.h"

namespace sarmap {
namespace viewer {
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

ViewerLimits LimitsOf(const ViewerNodeOptions& options) {
  ViewerLimits limits;
  limits.forget_after_s = options.forget_after_s;
  limits.max_deputies = options.max_deputies;
  limits.max_commands_per_deputy = options.max_commands_per_deputy;
  limits.max_nodes = options.max_nodes;
  limits.max_items = options.max_items;
  limits.max_text_bytes = options.max_text_bytes;
  return limits;
}

}  // namespace

ViewerNode::ViewerNode(const ViewerNodeOptions& options, common::Node* node)
    : options_(options), state_(LimitsOf(options)) {
  ServerOptions server_options;
  server_options.bind_address = options_.bind_address;
  server_options.port = options_.port;
  if (!options_.token_file.empty()) server_options.token = ReadToken(options_.token_file);
  server_options.threads = options_.http_threads;
  server_options.connection_limit_s = options_.http_connection_limit_s;
  server_options.io_timeout_s = options_.http_io_timeout_s;
  Subscribe(node);
  server_ = std::make_unique<ViewerServer>(&state_, server_options);
  server_->Start();
  SARMAP_LOG(INFO) << "serving http://" << options_.bind_address << ":" << server_->port() << "/"
                   << (server_options.token.empty() ? " (no access token)"
                                                    : " (access token required)");
}

ViewerNode::~ViewerNode() { Finish(); }

void ViewerNode::Finish() {
  if (server_) server_->Stop();
}

void ViewerNode::Subscribe(common::Node* node) {
  node->Subscribe<occupancy_grid_t>(
      "MAP",
      [this](const occupancy_grid_t& m, const common::ReceiveInfo&) {
        GridImage grid;
        common::CopyGridGeometry(m, &grid);
        std::string error;
        if (!common::DecodeOccupancyGrid(m, &grid.cells, &error)) {
          SARMAP_LOG(WARN) << "bad MAP: " << common::EscapeForLog(error, 512);
          return;
        }
        state_.SetMap(std::move(grid));
      },
      1);
  node->Subscribe<pose_t>("POSE", [this](const pose_t& m, const common::ReceiveInfo&) {
    map_from_base_ = common::ToRigid3d(m.position_m, m.orientation).ToRigid2d();
    state_.SetPose(m.header.utime, map_from_base_.translation().x(),
                   map_from_base_.translation().y(), map_from_base_.yaw_rad());
  });
  node->Subscribe<laser_scan_t>(
      "SCAN",
      [this](const laser_scan_t& m, const common::ReceiveInfo&) {
        state_.SetScan(ScanPointsInMap(m, map_from_base_));
      },
      1);
  node->Subscribe<people_map_t>(
      "PEOPLE_MAP",
      [this](const people_map_t& m, const common::ReceiveInfo&) {
        state_.SetPeople(PeopleViews(m));
      },
      5);
  node->Subscribe<sound_map_t>(
      "SOUND_MAP",
      [this](const sound_map_t& m, const common::ReceiveInfo&) {
        state_.SetSources(SourceViews(m));
      },
      5);
  node->Subscribe<image_t>(
      "RGB",
      [this](const image_t& m, const common::ReceiveInfo&) {
        if (m.compression == image_t::COMPRESSION_JPEG) {
          state_.SetCameraJpeg(m.data);
          return;
        }
        std::vector<uint8_t> rgb;
        std::string error;
        if (!common::DecodeColorImage(m, &rgb, &error)) return;
        state_.SetCameraJpeg(common::MakeColorImage(m.header, m.intrinsics, rgb.data(), m.width,
                                                    m.height, options_.camera_jpeg_quality)
                                 .data);
      },
      1);
  node->Subscribe<pm_info_t>(
      "PM_INFO",
      [this](const pm_info_t& m, const common::ReceiveInfo&) {
        state_.SetProcesses(m.deputy_id, ProcessViews(m), common::SteadySeconds());
      },
      20);
  node->Subscribe<node_status_t>(
      "NODE_STATUS",
      [this](const node_status_t& m, const common::ReceiveInfo&) {
        state_.SetNode(NodeViewOf(m, common::SteadySeconds()));
      },
      50);
  node->Subscribe<explore_status_t>(
      "EXPLORE_STATUS",
      [this](const explore_status_t& m, const common::ReceiveInfo&) {
        state_.SetMission(MissionViewOf(m));
      },
      1);
}

}  // namespace viewer
}  // namespace sarmap
