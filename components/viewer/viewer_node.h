#pragma once
// ViewerNode: the LCM adapter of the operator's web page. Subscribes to MAP, POSE, SCAN,
// PEOPLE_MAP, SOUND_MAP, RGB, EXPLORE_STATUS, PM_INFO and NODE_STATUS into a ViewerState and
// serves it over HTTP (read-only, ViewerServer) until the node stops.

#include <memory>

#include "common/node.h"
#include "common/transform.h"
#include "viewer/viewer_options.h"
#include "viewer/viewer_server.h"
#include "viewer/viewer_state.h"

namespace sarmap {
namespace viewer {

class ViewerNode {
 public:
  // Starts the HTTP server. Throws std::runtime_error for an unreadable or short token file
  // or a port that cannot be bound.
  ViewerNode(const ViewerNodeOptions& options, common::Node* node);
  ~ViewerNode();

  // Stops the HTTP server.
  void Finish();

  const ViewerState& state() const { return state_; }
  int port() const { return server_->port(); }

 private:
  void Subscribe(common::Node* node);

  ViewerNodeOptions options_;
  ViewerState state_;
  common::Rigid2d map_from_base_;
  std::unique_ptr<ViewerServer> server_;
};

}  // namespace viewer
}  // namespace sarmap
