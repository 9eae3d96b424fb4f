#pragma once
// Watching a node process from a test driver over LCM: its NODE_STATUS reports, and handling
// messages until a condition holds.

#include <chrono>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <regex>
#include <string>
#include <utility>

#include "sarmap/node_status_t.hpp"

namespace sarmap {
namespace testing {

// The last NODE_STATUS of one node: its message, and the inputs it dropped as malformed.
struct NodeStatusSink {
  explicit NodeStatusSink(std::string node) : node_name(std::move(node)) {}
  void OnStatus(const lcm::ReceiveBuffer*, const std::string&, const node_status_t* s) {
    if (s->node_name != node_name) return;
    message = s->message;
    dropped = 0;
    for (const auto& c : s->channels) dropped += c.dropped_malformed;
  }
  // The count after "input_warnings " in the message; none before the node reports it.
  std::optional<int> InputWarnings() const {
    std::smatch m;
    if (!std::regex_search(message, m, std::regex("input_warnings (\\d+)"))) return std::nullopt;
    return std::stoi(m[1]);
  }

  std::string node_name;
  std::string message;
  int64_t dropped = 0;
};

// Handles `lcm`'s messages until done() holds or timeout_s have passed; returns done().
template <class Done>
bool SpinUntil(lcm::LCM& lcm, Done done, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done() && std::chrono::steady_clock::now() < end) lcm.handleTimeout(50);
  return done();
}

}  // namespace testing
}  // namespace sarmap
