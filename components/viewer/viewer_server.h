#pragma once
// The HTTP side of the viewer: the page, /api/state (JSON), /api/map.png, /api/camera.jpg.
// Read-only (GET only), bound to a configured address, with an optional access token
// (?token=... or "Authorization: Bearer ..."). Every connection is served for at most
// connection_limit_s in all (each read or write waits at most io_timeout_s), so slow or idle
// clients hold a worker thread for a bounded time and cannot lock others out.

#include <memory>
#include <string>
#include <thread>

#include "viewer/viewer_state.h"

namespace httplib {
class Server;
}

namespace sarmap {
namespace viewer {

class BoundedServer;

struct ServerOptions {
  std::string bind_address = "127.0.0.1";
  int port = 8080;  // 0: any free port
  std::string token;
  int threads = 16;                   // worker threads (connections served at once)
  double connection_limit_s = 10.0;   // a connection is closed after this long in all
  double io_timeout_s = 3.0;          // one read or write waits at most this long
  int keep_alive_max_requests = 100;  // requests per connection
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
  std::unique_ptr<BoundedServer> server_;
  std::thread thread_;
  int port_ = 0;
};

}  // namespace viewer
}  // namespace sarmap
