#pragma once
// Authenticated orders and reports. procman lets any host on the multicast group make a
// deputy run anything and tell the sheriff anything; ours signs both directions with a
// shared key:
//
//   hmac_sha256 = HMAC-SHA256(key, LCM encoding of the message with hmac_sha256 zeroed)
//
// Freshness comes from the deputy, not from a file or the sheriff's clock:
// - every deputy start begins a new random *session*; its signed PM_INFO carries the session
//   and the session's monotonic clock (microseconds since the deputy started);
// - orders name the session they are for (deputy_session) and carry a counter on that
//   session's clock, as the sheriff estimates it from the last verified PM_INFO. A deputy
//   accepts a counter only above the last one of that sheriff instance and within
//   `window` of its own session clock;
// - a sheriff accepts a new session for a deputy only from a PM_INFO that echoes the nonce
//   of one of its own signed probes, and within a session only reports whose clock is newer.
//
// So a captured order is useless once its deputy restarts (another session) and once it
// is older than the window; no counter can lock a sheriff out beyond the window; and a
// recorded PM_INFO cannot be played back as current state.
//
// This uses only the generated message types (their encoders), not the LCM runtime.

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "sarmap/pm_info_t.hpp"
#include "sarmap/pm_orders_t.hpp"
#include "sarmap/pm_output_t.hpp"

namespace sarmap {
namespace procman {

// pm_orders_t with this deputy_id and no commands is a probe: every deputy publishes PM_INFO
// at once (so a sheriff starting up need not wait a second), at most 20 times a second. It
// orders nothing. A signed probe carries a nonce in `counter` that the deputy echoes in
// PM_INFO (probe_echo): the sheriff's proof that a report is live, not a recording.
constexpr const char* kProbeDeputyId = "*";

using Key = std::vector<uint8_t>;
using Digest = std::array<uint8_t, 32>;

constexpr size_t kMinKeyBytes = 16;

// Reads a key file (raw bytes, e.g. 32 from /dev/urandom; "~/" is the user's home). Throws std::runtime_error when
// it is missing, shorter than kMinKeyBytes, or readable by group or others.
Key LoadKeyFile(const std::string& path);

Digest HmacSha256(const Key& key, const uint8_t* data, size_t size);

// Fills orders->hmac_sha256. Throws std::runtime_error when the orders cannot be encoded (a
// string holds a NUL byte).
void SignOrders(const Key& key, sarmap::pm_orders_t* orders);
void SignInfo(const Key& key, sarmap::pm_info_t* info);
void SignOutput(const Key& key, sarmap::pm_output_t* output);
// True when hmac_sha256 matches (constant-time comparison); false, never a throw, for
// messages that cannot be encoded (whatever arrives from the bus comes here).
bool SignatureValid(const Key& key, const sarmap::pm_orders_t& orders);
bool SignatureValid(const Key& key, const sarmap::pm_info_t& info);
bool SignatureValid(const Key& key, const sarmap::pm_output_t& output);
// All 32 bytes zero.
bool IsUnsigned(const uint8_t (&hmac_sha256)[32]);

// A random positive 63-bit number (getrandom): deputy sessions and probe nonces.
int64_t RandomNonce();

enum class Verdict { kAccepted, kUnsigned, kForged, kReplayed, kOtherSession, kOutOfWindow };
const char* ToString(Verdict verdict);

// The deputy's replay guard for one session. `now_us` is always the deputy's session clock.
//
//   fresh(id, s, c)  <=>  s == session  and  |c - now| <= window  and  c > last[id]
//
// - a captured order of an earlier session (the deputy restarted) is refused;
// - an order is never accepted twice (c <= last[id]), and never once it is older than the
//   window, so instances silent for longer than the window are forgotten: memory is bounded
//   by the orders of one window;
// - a counter far ahead of the deputy's clock (INT64_MAX) is refused, so one order can hold
//   a sheriff instance back by at most the window; other instances of the same sheriff name
//   are not affected;
// - a live sheriff and a one-shot command interleave freely (separate instances).
class ReplayGuard {
 public:
  static constexpr int64_t kDefaultWindowUs = 5000000;
  explicit ReplayGuard(int64_t session, int64_t window_us = kDefaultWindowUs);
  int64_t session() const { return session_; }
  int64_t window_us() const { return window_us_; }
  Verdict Check(const std::string& sheriff_id, int64_t deputy_session, int64_t counter,
                int64_t now_us) const;
  void Accept(const std::string& sheriff_id, int64_t counter, int64_t now_us);
  // Last counter accepted from this sheriff instance; -1 if none (or forgotten).
  int64_t Last(const std::string& sheriff_id) const;
  size_t instances() const { return last_.size(); }

 private:
  int64_t session_;
  int64_t window_us_;
  std::map<std::string, int64_t> last_;  // per sheriff_id
};

// Checks signature, session, window and counter; on kAccepted records the counter.
Verdict VerifyOrders(const Key& key, const sarmap::pm_orders_t& orders, ReplayGuard* guard,
                     int64_t now_us);

enum class InfoVerdict { kAccepted, kNewSession, kUnsigned, kForged, kStale, kUnconfirmed };
const char* ToString(InfoVerdict verdict);

// The sheriff's check of PM_INFO from the deputies it orders (keyed by deputy id).
// kAccepted: signed, same session, clock newer than the last accepted report.
// kNewSession: signed, another session, echoing a nonce of our probes newer than the one
// the deputy's current session was confirmed with (a restarted deputy answering our probe).
// kUnconfirmed: signed, another session, no fresh echo: send a probe, then it confirms
// (or it is a recording of an earlier session, and never does).
class InfoGuard {
 public:
  // A nonce this sheriff just sent in a signed probe.
  void AddChallenge(int64_t nonce);
  InfoVerdict Verify(const Key& key, const sarmap::pm_info_t& info);
  // PM_OUTPUT of a deputy: kAccepted when signed, of the deputy's confirmed session (its
  // reports confirm it; an earlier session's output is kUnconfirmed) and newer
  // (session_clock_us) than the last output accepted from that session (else kStale).
  InfoVerdict VerifyOutput(const Key& key, const sarmap::pm_output_t& output);
  // The confirmed session of a deputy; 0 if none yet.
  int64_t Session(const std::string& deputy_id) const;

 private:
  struct Seen {
    int64_t session = 0;
    int64_t clock_us = -1;
    int64_t challenge_index = -1;  // of the nonce that confirmed the session
    int64_t output_clock_us = -1;  // of the last output accepted in the session
  };
  std::map<std::string, Seen> seen_;
  std::vector<std::pair<int64_t, int64_t>> challenges_;  // (index, nonce), the last 8
  int64_t next_index_ = 0;
};

}  // namespace procman
}  // namespace sarmap
