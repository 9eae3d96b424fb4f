#include "viewer/viewer_server.h"

#include <arpa/inet.h>
#include <httplib.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "common/time.h"
#include "viewer/index_html.h"

namespace sarmap {
namespace viewer {

namespace {

double SteadyNow() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A connection's socket with one deadline for the whole connection: each read or write waits
// at most io_timeout_s and never past the deadline. (cpp-httplib's own timeouts apply per
// read, so a client sending a byte every few seconds could hold a worker forever.)
class DeadlineStream : public httplib::Stream {
 public:
  DeadlineStream(int sock, double deadline_s, double io_timeout_s)
      : sock_(sock), deadline_s_(deadline_s), io_timeout_s_(io_timeout_s) {}

  bool is_readable() const override { return begin_ < end_ || Wait(POLLIN, io_timeout_s_); }
  bool is_writable() const override { return Wait(POLLOUT, io_timeout_s_); }
  ssize_t read(char* ptr, size_t size) override {
    if (begin_ == end_) {
      if (!Wait(POLLIN, io_timeout_s_)) return -1;
      const ssize_t n = recv(sock_, buffer_, sizeof(buffer_), 0);
      if (n <= 0) return n;
      begin_ = 0;
      end_ = static_cast<size_t>(n);
    }
    const size_t n = std::min(size, end_ - begin_);
    std::copy(buffer_ + begin_, buffer_ + begin_ + n, ptr);
    begin_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!Wait(POLLOUT, io_timeout_s_)) return -1;
    return send(sock_, ptr, size, MSG_NOSIGNAL);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    Address(getpeername, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    Address(getsockname, ip, port);
  }
  socket_t socket() const override { return sock_; }
  // Waits for the next request on a kept-alive connection.
  bool WaitForRequest(double timeout_s) const { return begin_ < end_ || Wait(POLLIN, timeout_s); }
  bool Expired() const { return SteadyNow() >= deadline_s_; }

 private:
  bool Wait(short events, double timeout_s) const {
    const double left_s = std::min(timeout_s, deadline_s_ - SteadyNow());
    if (left_s <= 0) return false;
    pollfd p{sock_, events, 0};
    int r;
    while ((r = poll(&p, 1, static_cast<int>(std::ceil(left_s * 1000)))) < 0 && errno == EINTR) {
    }
    return r > 0 && (p.revents & (events | POLLHUP | POLLERR));
  }
  template <class F>
  void Address(F get, std::string& ip, int& port) const {
    sockaddr_storage addr{};
    socklen_t len = sizeof(addr);
    ip.clear();
    port = 0;
    if (get(sock_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return;
    char text[INET6_ADDRSTRLEN] = {0};
    if (addr.ss_family == AF_INET) {
      const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
      inet_ntop(AF_INET, &a->sin_addr, text, sizeof(text));
      port = ntohs(a->sin_port);
    } else if (addr.ss_family == AF_INET6) {
      const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
      inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof(text));
      port = ntohs(a->sin6_port);
    }
    ip = text;
  }

  int sock_;
  double deadline_s_;
  double io_timeout_s_;
  char buffer_[4096];
  size_t begin_ = 0, end_ = 0;
};

}  // namespace

// cpp-httplib's server with a bounded worker pool and the connection handling above.
class BoundedServer : public httplib::Server {
 public:
  explicit BoundedServer(const ServerOptions& options) : options_(options) {
    const size_t threads = static_cast<size_t>(std::max(1, options.threads));
    new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  }

 private:
  bool process_and_close_socket(socket_t sock) override {
    DeadlineStream stream(sock, SteadyNow() + options_.connection_limit_s, options_.io_timeout_s);
    bool ok = false;
    for (int left = std::max(1, options_.keep_alive_max_requests); left > 0; --left) {
      if (svr_sock_ == INVALID_SOCKET || !stream.WaitForRequest(options_.io_timeout_s)) break;
      bool closed = false;
      ok = process_request(stream, left == 1 || stream.Expired(), closed, nullptr);
      if (!ok || closed) break;
    }
    shutdown(sock, SHUT_RDWR);
    close(sock);
    return ok;
  }

  ServerOptions options_;
};

ViewerServer::ViewerServer(const ViewerState* state, ServerOptions options)
    : state_(state),
      options_(std::move(options)),
      server_(std::make_unique<BoundedServer>(options_)) {}

ViewerServer::~ViewerServer() { Stop(); }

bool ViewerServer::Authorised(const std::string& query_token,
                              const std::string& authorization) const {
  if (options_.token.empty()) return true;
  // Constant-time comparison: the token guards a robot's live view.
  const auto same = [&](const std::string& a) {
    if (a.size() != options_.token.size()) return false;
    unsigned char diff = 0;
    for (size_t i = 0; i < a.size(); ++i)
      diff |= static_cast<unsigned char>(a[i] ^ options_.token[i]);
    return diff == 0;
  };
  return same(query_token) ||
         (authorization.rfind("Bearer ", 0) == 0 && same(authorization.substr(7)));
}

void ViewerServer::Start() {
  server_->set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (req.method != "GET" && req.method != "HEAD") {
      res.status = 405;
      res.set_content("read-only\n", "text/plain");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (!Authorised(req.get_param_value("token"), req.get_header_value("Authorization"))) {
      res.status = 401;
      res.set_content("access token required: open the page as /?token=...\n", "text/plain");
      return httplib::Server::HandlerResponse::Handled;
    }
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Content-Type-Options", "nosniff");
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server_->Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(kIndexHtml, "text/html; charset=utf-8");
  });
  server_->Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(state_->Json(common::SteadySeconds()), "application/json");
  });
  server_->Get("/api/map.png", [this](const httplib::Request&, httplib::Response& res) {
    const auto png = state_->MapPng();
    if (png.empty()) {
      res.status = 404;
      return;
    }
    res.set_content(reinterpret_cast<const char*>(png.data()), png.size(), "image/png");
  });
  server_->Get("/api/camera.jpg", [this](const httplib::Request&, httplib::Response& res) {
    const auto jpeg = state_->CameraJpeg();
    if (jpeg.empty()) {
      res.status = 404;
      return;
    }
    res.set_content(reinterpret_cast<const char*>(jpeg.data()), jpeg.size(), "image/jpeg");
  });
  if (options_.port == 0) {
    port_ = server_->bind_to_any_port(options_.bind_address);
  } else {
    port_ = server_->bind_to_port(options_.bind_address, options_.port) ? options_.port : -1;
  }
  if (port_ <= 0) {
    throw std::runtime_error("cannot listen on " + options_.bind_address + ":" +
                             std::to_string(options_.port));
  }
  thread_ = std::thread([this] { server_->listen_after_bind(); });
}

void ViewerServer::Stop() {
  if (thread_.joinable()) {
    server_->stop();
    thread_.join();
  }
}

}  // namespace viewer
}  // namespace sarmap
