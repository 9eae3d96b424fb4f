#pragma once
// The HTTP side of the viewer: the page, /api/state (JSON), /api/map.png, /api/camera.jpg.
// Read-only (GET only), bound to a configured address, with an optional access token
// (?token=... or "Authorization: Bearer ...").

#include <memory>
#include <string>
#include <thread>

#include "viewer/viewer_state.h"

namespace httplib {
class Server;
}

namespace sarmap {
namespace viewer {

struct ServerOptions {
  std::string bind_address = "127.0.0.1";
  int port = 8080;  // 0: any free port
  std::string token;
};

class ViewerServer {
 public:
  ViewerServer(const ViewerState* state, ServerOptions options);
  ~ViewerServer();
  // Binds and serves in a background thread; throws std::runtime_error when it cannot bind.
  void Start();
  void Stop();
  int port() const { return port_; }

 private:
  bool Authorised(const std::string& query_token, const std::string& authorization) const;
  const ViewerState* state_;
  ServerOptions options_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int port_ = 0;
};

}  // namespace viewer
}  // namespace sarmap
