#pragma once
// sarmap-viewer's options (config/viewer.yaml).
#include <string>

#include "common/options.h"

namespace sarmap {
namespace viewer {

struct ViewerNodeOptions {
  std::string bind_address = "127.0.0.1";
  int port = 8080;
  std::string token_file;  // "" = no token (only sensible on a closed network)
  int camera_jpeg_quality = 70;
  int http_threads = 16;
  double http_connection_limit_s = 10.0;
  double http_io_timeout_s = 3.0;
  double forget_after_s = 60.0;
  int max_deputies = 16;
  int max_commands_per_deputy = 64;
  int max_nodes = 64;
  int max_items = 2000;
  int max_text_bytes = 200;
  template <class V>
  void Visit(V& v) {
    v("bind_address", bind_address, "address to listen on (0.0.0.0 for the robot's network: then set a token_file)");
    v("port", port, "HTTP port");
    v("token_file", token_file, "file holding the access token (one line, at least 8 characters); \"\" serves without a "
      "token");
    v("camera_jpeg_quality", camera_jpeg_quality,
      "quality of the re-encoded thumbnail when RGB is not JPEG", InRange(1, 100));
    v("http_threads", http_threads, "connections served at once", InRange(1, 256));
    v("http_connection_limit_s", http_connection_limit_s,
      "a connection is closed after this long in all", Positive());
    v("http_io_timeout_s", http_io_timeout_s,
      "one read or write of a connection waits at most this long", Positive());
    v("forget_after_s", forget_after_s,
      "deputies and nodes not heard from this long leave the page", Positive());
    v("max_deputies", max_deputies, "deputies shown at most (the least recently heard goes first)",
      InRange(1, 1000));
    v("max_commands_per_deputy", max_commands_per_deputy, "commands shown per deputy at most",
      InRange(1, 10000));
    v("max_nodes", max_nodes,
      "nodes (NODE_STATUS) kept at most (the least recently heard goes first)", InRange(1, 10000));
    v("max_items", max_items, "people, sound sources, scan points and path points shown at most",
      InRange(1, 100000));
    v("max_text_bytes", max_text_bytes,
      "longest string from the bus shown (names, keywords, messages)", InRange(8, 4096));
  }
  void Validate(common::Validator& check) const {
    check.That(port >= 0 && port < 65536, "port", "must be 0..65535");
  }
};

}  // namespace viewer
}  // namespace sarmap
