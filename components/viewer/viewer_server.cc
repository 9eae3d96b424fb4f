#include "viewer/viewer_server.h"

#include <httplib.h>

#include <stdexcept>

#include "common/time.h"
#include "viewer/index_html.h"

namespace sarmap {
namespace viewer {

ViewerServer::ViewerServer(const ViewerState* state, ServerOptions options)
    : state_(state), options_(std::move(options)), server_(std::make_unique<httplib::Server>()) {}

ViewerServer::~ViewerServer() { Stop(); }

bool ViewerServer::Authorised(const std::string& query_token, const std::string& authorization) const {
  if (options_.token.empty()) return true;
  // Constant-time comparison: the token guards a robot's live view.
  const auto same = [&](const std::string& a) {
    if (a.size() != options_.token.size()) return false;
    unsigned char diff = 0;
    for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ options_.token[i]);
    return diff == 0;
  };
  return same(query_token) || (authorization.rfind("Bearer ", 0) == 0 && same(authorization.substr(7)));
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
    throw std::runtime_error("cannot listen on " + options_.bind_address + ":" + std::to_string(options_.port));
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
