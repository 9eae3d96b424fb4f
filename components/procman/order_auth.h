#pragma once
// Authenticated orders. procman lets any host on the multicast group make a deputy run
// anything; ours only obeys orders signed with a shared key:
//
//   hmac_sha256 = HMAC-SHA256(key, LCM encoding of the pm_orders_t with hmac_sha256 zeroed)
//
// and whose counter is strictly greater than the last one accepted from that sheriff (per
// sheriff_id, persisted so that a restarted deputy does not re-open old orders to replay).
// Sheriffs take the counter from wall-clock microseconds (never below last + 1), so a
// restarted sheriff continues upward without storing anything.
//
// This uses only the generated message type (its encoder), not the LCM runtime.

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "sarmap/pm_orders_t.hpp"

namespace sarmap {
namespace procman {

// pm_orders_t with this deputy_id and no commands is a probe: every deputy publishes PM_INFO
// at once (so a sheriff starting up need not wait a second). It orders nothing, so it needs
// no signature, and deputies rate-limit their answers.
constexpr const char* kProbeDeputyId = "*";

using Key = std::vector<uint8_t>;
using Digest = std::array<uint8_t, 32>;

constexpr size_t kMinKeyBytes = 16;

// Reads a key file (raw bytes, e.g. 32 from /dev/urandom). Throws std::runtime_error when
// it is missing, shorter than kMinKeyBytes, or readable by group or others.
Key LoadKeyFile(const std::string& path);
// $SARMAP_PROCMAN_KEY, else ~/.config/sarmap/procman.key.
std::string DefaultKeyPath();

Digest HmacSha256(const Key& key, const uint8_t* data, size_t size);

// Fills orders->hmac_sha256. Throws std::runtime_error when the orders cannot be encoded (a
// string holds a NUL byte).
void SignOrders(const Key& key, sarmap::pm_orders_t* orders);
// True when hmac_sha256 matches (constant-time comparison); false, never a throw, for orders
// that cannot be encoded (whatever arrives from the bus comes here).
bool SignatureValid(const Key& key, const sarmap::pm_orders_t& orders);

enum class Verdict { kAccepted, kUnsigned, kForged, kReplayed };
const char* ToString(Verdict verdict);

// A sheriff_id is "NAME" or "NAME/INSTANCE" (the sheriff uses sheriff@host/PID). Counters are
// checked per instance, and every instance of a NAME (the replay domain) is held to that
// NAME's newest counter:
//
//   fresh(id, c)  <=>  c > last[id] (if id was seen)  and  c > newest[NAME(id)] - window
//
// - an order the deputy accepted is never accepted again (c <= last[id]), also after a deputy
//   restart (persisted);
// - a restarted sheriff (new instance, counters from the wall clock) continues upward;
// - two instances of one NAME running at once (a live sheriff and a one-shot command) may
//   interleave within `window` without false refusals;
// - instances whose last counter fell more than `window` behind their NAME's newest are
//   forgotten (the state file stays small): their orders fail the NAME rule anyway.
std::string ReplayDomain(const std::string& sheriff_id);

class ReplayGuard {
 public:
  static constexpr int64_t kDefaultWindowUs = 2000000;
  // state_path "" keeps the counters in memory only. Throws std::runtime_error on an
  // unreadable or corrupt state file (a deputy must not silently forget its counters).
  explicit ReplayGuard(std::string state_path = "", int64_t window_us = kDefaultWindowUs);
  bool Fresh(const std::string& sheriff_id, int64_t counter) const;
  // Records the counter; returns false when persisting failed (logged by the caller).
  bool Accept(const std::string& sheriff_id, int64_t counter);
  // Last counter accepted from exactly this sheriff_id; -1 if none (or forgotten).
  int64_t Last(const std::string& sheriff_id) const;
  // Newest counter accepted from any instance of the id's NAME; -1 if none.
  int64_t Newest(const std::string& sheriff_id) const;
  const std::string& state_path() const { return state_path_; }

 private:
  std::string state_path_;
  int64_t window_us_;
  std::map<std::string, int64_t> last_;  // per full sheriff_id
};

// Checks signature, then freshness; on kAccepted records the counter in `guard`.
// `persisted` (optional) is false when recording the counter on disk failed.
Verdict VerifyOrders(const Key& key, const sarmap::pm_orders_t& orders, ReplayGuard* guard,
                     bool* persisted = nullptr);

// Sheriff side: strictly increasing counters derived from the wall clock (microseconds).
class CounterSource {
 public:
  int64_t Next();

 private:
  int64_t last_ = 0;
};

}  // namespace procman
}  // namespace sarmap
