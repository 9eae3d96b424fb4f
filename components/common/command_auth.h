#pragma once
// Signed commands. CMD_VEL and TELEOP move the robot, and any host on the LCM group can
// publish them; with a command key configured (a file of at least 16 random bytes, mode 600:
// the launcher's procman key serves), the sender signs each message and the receiver acts
// only on messages that carry a valid signature and are newer than the last one it acted on:
//
//   hmac_sha256 = HMAC-SHA256(key, LCM encoding of the message with hmac_sha256 zeroed)
//
// "Newer" is header.utime strictly above the last accepted one, so a recorded command played
// back later moves nothing; a receiver that has a clock also refuses commands stamped far
// ahead of it. Uses only the generated message types, not the LCM runtime.

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace sarmap {
namespace common {

using AuthKey = std::vector<uint8_t>;
using AuthDigest = std::array<uint8_t, 32>;

// `path` with a leading "~/" replaced by the user's home directory (from the password
// database, so that a key's location does not depend on the environment).
std::string ExpandUserHome(const std::string& path);

// Reads a key file (raw bytes; "~/" is the user's home). Throws std::runtime_error when it is
// missing, shorter than 16 bytes, or readable by group or others.
AuthKey LoadAuthKeyFile(const std::string& path_as_given);

AuthDigest HmacSha256(const AuthKey& key, const uint8_t* data, size_t size);

// Constant-time comparison of two digests.
bool DigestsEqual(const AuthDigest& a, const uint8_t* b);

// Digest of `msg` with its hmac_sha256 zeroed; false when the message has no LCM encoding (a
// string holding a NUL byte, which only a hostile sender puts there).
template <class T>
bool MessageDigest(const AuthKey& key, const T& msg, AuthDigest* digest) {
  T copy = msg;
  std::fill(std::begin(copy.hmac_sha256), std::end(copy.hmac_sha256), 0);
  const int size = copy.getEncodedSize();
  if (size <= 0) return false;
  std::vector<uint8_t> buffer(static_cast<size_t>(size));
  if (copy.encode(buffer.data(), 0, size) != size) return false;
  *digest = HmacSha256(key, buffer.data(), buffer.size());
  return true;
}

// Fills msg->hmac_sha256; false when the message cannot be encoded.
template <class T>
bool SignMessage(const AuthKey& key, T* msg) {
  AuthDigest d;
  if (!MessageDigest(key, *msg, &d)) return false;
  std::copy(d.begin(), d.end(), std::begin(msg->hmac_sha256));
  return true;
}

// True when hmac_sha256 is the message's signature under `key`; never throws.
template <class T>
bool MessageSigned(const AuthKey& key, const T& msg) {
  AuthDigest d;
  return MessageDigest(key, msg, &d) && DigestsEqual(d, std::begin(msg.hmac_sha256));
}

// The receiving side: with an empty key every command is accepted (and `Describe` says the
// commands are not authenticated); with a key, only signed commands newer than the last
// accepted one.
class CommandGate {
 public:
  CommandGate() = default;
  explicit CommandGate(AuthKey key) : key_(std::move(key)) {}
  bool enabled() const { return !key_.empty(); }

  // True when the command may act; otherwise `*why` says why not. With `now_utime` (the
  // receiver's clock, > 0), a command stamped more than `max_ahead_us` ahead of it is refused
  // and not adopted as the newest: a sender that stamps its commands with its input's time
  // (the explorer: the scan's) can be made to sign a far-future stamp by a forged input, and
  // adopting it would make every later real command look like a replay.
  template <class T>
  bool Accept(const T& msg, std::string* why, int64_t now_utime = 0,
              int64_t max_ahead_us = 5000000) {
    if (key_.empty()) return true;
    if (!MessageSigned(key_, msg)) {
      if (why) *why = "not signed with the command key";
      return false;
    }
    if (now_utime > 0 && msg.header.utime > now_utime + max_ahead_us) {
      if (why) *why = "stamped ahead of this clock";
      return false;
    }
    if (has_last_ && msg.header.utime <= last_utime_) {
      if (why) *why = "not newer than the last command (a replay)";
      return false;
    }
    has_last_ = true;
    last_utime_ = msg.header.utime;
    return true;
  }

 private:
  AuthKey key_;
  bool has_last_ = false;
  int64_t last_utime_ = 0;
};

}  // namespace common
}  // namespace sarmap
