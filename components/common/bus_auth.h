#pragma once
// The signed bus. Any host on the LCM group can publish on any channel, so a forged POSE, MAP,
// PEOPLE_MAP or AUDIO would steer the explorer, blind the maps or be taken as the microphone.
// With a bus key (a file of at least 16 random bytes, mode 600: common/command_auth.h's
// LoadAuthKeyFile), every message a node publishes carries a trailer after its LCM encoding
// (common/bus_trailer.h):
//
//   "SMB1" | session | counter | HMAC-SHA256(key, channel | 0x00 | encoding | "SMB1" | session |
//   counter)
//
// session: 8 random bytes drawn when the publishing process starts; counter: rises by one with
// every message the process publishes, on any channel. A node with the key acts only on a
// message whose trailer verifies for the channel it arrived on and whose counter is above the
// last one it accepted from that session on that channel: a forged, altered, re-addressed or
// played-back message is counted and dropped before it is decoded. Each channel remembers the
// last kBusSessionsPerChannel sessions (a restarted publisher is a new session), so the state is
// bounded; a capture of a session older than those is accepted once per message and then meets
// the nodes' stamp gates (common/stamp_gate.h) like any stale input.
//
// Nodes without the key, the recorder and every log reader strip a trailer and read the message
// as it is (they can then show a signed bus but do not vouch for it).

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/bus_trailer.h"
#include "common/command_auth.h"

namespace sarmap {
namespace common {

constexpr size_t kBusSessionsPerChannel = 8;

class BusAuth {
 public:
  // Unkeyed: Sign does nothing, Verify accepts everything.
  BusAuth();
  // Keyed, with a fresh random session.
  explicit BusAuth(AuthKey key);

  bool keyed() const { return !key_.empty(); }
  void SetKey(AuthKey key) { key_ = std::move(key); }

  // Appends the trailer to `encoding` (the message's LCM bytes) for `channel`; nothing when
  // unkeyed.
  void Sign(const std::string& channel, std::vector<uint8_t>* encoding);

  // True when the message may be acted on; then *payload_size is the encoding's size without
  // the trailer (the whole size when unkeyed). False with a reason in *why otherwise.
  bool Verify(const std::string& channel, const uint8_t* data, size_t size, size_t* payload_size,
              std::string* why);

  // The digest a trailer carries (exposed for tests).
  AuthDigest Digest(const std::string& channel, const uint8_t* data, size_t payload_size,
                    const uint8_t* trailer_head) const;

 private:
  struct SessionState {
    uint64_t last_counter = 0;
    uint64_t last_used = 0;  // verifications so far when the session last passed
  };
  AuthKey key_;
  std::array<uint8_t, 8> session_{};
  uint64_t counter_ = 0;
  uint64_t verified_ = 0;
  std::map<std::string, std::map<uint64_t, SessionState>> sessions_;  // channel -> session
};

}  // namespace common
}  // namespace sarmap
