#include "procman/order_auth.h"

#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/command_auth.h"

namespace sarmap {
namespace procman {

// One key-file reader and one HMAC for the launcher and the signed commands.
Key LoadKeyFile(const std::string& path) { return common::LoadAuthKeyFile(path); }

Digest HmacSha256(const Key& key, const uint8_t* data, size_t size) {
  return common::HmacSha256(key, data, size);
}

namespace {

// Signing and checking are common/command_auth's, as for CMD_VEL and TELEOP.
template <class T>
void Sign(const Key& key, T* msg, const char* type) {
  if (!common::SignMessage(key, msg)) {
    throw std::runtime_error(std::string("cannot encode ") + type + " (a string holds a NUL byte)");
  }
}

template <class T>
bool Valid(const Key& key, const T& msg) {
  return common::MessageSigned(key, msg);
}

}  // namespace

void SignOrders(const Key& key, sarmap::pm_orders_t* orders) { Sign(key, orders, "pm_orders_t"); }
void SignInfo(const Key& key, sarmap::pm_info_t* info) { Sign(key, info, "pm_info_t"); }
void SignOutput(const Key& key, sarmap::pm_output_t* output) { Sign(key, output, "pm_output_t"); }
bool SignatureValid(const Key& key, const sarmap::pm_orders_t& orders) {
  return Valid(key, orders);
}
bool SignatureValid(const Key& key, const sarmap::pm_info_t& info) { return Valid(key, info); }
bool SignatureValid(const Key& key, const sarmap::pm_output_t& output) {
  return Valid(key, output);
}

bool IsUnsigned(const uint8_t (&hmac_sha256)[32]) {
  uint8_t any = 0;
  for (uint8_t b : hmac_sha256) any |= b;
  return any == 0;
}

int64_t RandomNonce() {
  uint64_t value = 0;
  while (value == 0) {
    if (getrandom(&value, sizeof(value), 0) != static_cast<ssize_t>(sizeof(value))) {
      throw std::runtime_error(std::string("getrandom: ") + strerror(errno));
    }
    value &= 0x7fffffffffffffffULL;
  }
  return static_cast<int64_t>(value);
}

const char* ToString(Verdict verdict) {
  switch (verdict) {
    case Verdict::kAccepted:
      return "accepted";
    case Verdict::kUnsigned:
      return "unsigned";
    case Verdict::kForged:
      return "forged (signature does not match the key)";
    case Verdict::kReplayed:
      return "replayed (counter not above the last accepted)";
    case Verdict::kOtherSession:
      return "for another deputy session (sent before this deputy started)";
    case Verdict::kOutOfWindow:
      return "counter outside the window around the deputy's clock";
  }
  return "?";
}

ReplayGuard::ReplayGuard(int64_t session, int64_t window_us)
    : session_(session), window_us_(window_us) {}

int64_t ReplayGuard::Last(const std::string& sheriff_id) const {
  auto it = last_.find(sheriff_id);
  return it == last_.end() ? -1 : it->second;
}

Verdict ReplayGuard::Check(const std::string& sheriff_id, int64_t deputy_session, int64_t counter,
                           int64_t now_us) const {
  if (deputy_session != session_) return Verdict::kOtherSession;
  // Written so that no subtraction can overflow, whatever the counter.
  if (counter < now_us - window_us_ || counter > now_us + window_us_) {
    return Verdict::kOutOfWindow;
  }
  if (counter <= Last(sheriff_id)) return Verdict::kReplayed;
  return Verdict::kAccepted;
}

void ReplayGuard::Accept(const std::string& sheriff_id, int64_t counter, int64_t now_us) {
  last_[sheriff_id] = std::max(counter, Last(sheriff_id));
  // Instances whose last order left the window: any order of theirs fails the window rule.
  for (auto it = last_.begin(); it != last_.end();) {
    if (it->second < now_us - window_us_) {
      it = last_.erase(it);
    } else {
      ++it;
    }
  }
}

Verdict VerifyOrders(const Key& key, const sarmap::pm_orders_t& orders, ReplayGuard* guard,
                     int64_t now_us) {
  if (IsUnsigned(orders.hmac_sha256)) return Verdict::kUnsigned;
  if (!SignatureValid(key, orders)) return Verdict::kForged;
  const Verdict v = guard->Check(orders.sheriff_id, orders.deputy_session, orders.counter, now_us);
  if (v == Verdict::kAccepted) guard->Accept(orders.sheriff_id, orders.counter, now_us);
  return v;
}

const char* ToString(InfoVerdict verdict) {
  switch (verdict) {
    case InfoVerdict::kAccepted:
      return "accepted";
    case InfoVerdict::kNewSession:
      return "new session";
    case InfoVerdict::kUnsigned:
      return "unsigned";
    case InfoVerdict::kForged:
      return "forged (signature does not match the key)";
    case InfoVerdict::kStale:
      return "stale (not newer than the last report of that session)";
    case InfoVerdict::kUnconfirmed:
      return "unconfirmed session (no echo of a probe of ours)";
  }
  return "?";
}

void InfoGuard::AddChallenge(int64_t nonce) {
  challenges_.emplace_back(next_index_++, nonce);
  if (challenges_.size() > 8) challenges_.erase(challenges_.begin());
}

InfoVerdict InfoGuard::Verify(const Key& key, const sarmap::pm_info_t& info) {
  if (IsUnsigned(info.hmac_sha256)) return InfoVerdict::kUnsigned;
  if (!SignatureValid(key, info)) return InfoVerdict::kForged;
  Seen& seen = seen_[info.deputy_id];
  if (seen.session != 0 && info.session == seen.session) {
    if (info.session_clock_us <= seen.clock_us) return InfoVerdict::kStale;
    seen.clock_us = info.session_clock_us;
    return InfoVerdict::kAccepted;
  }
  for (const auto& [index, nonce] : challenges_) {
    // Only a nonce newer than the one that confirmed the current session: a recording of an
    // earlier session that echoed an older probe of ours cannot bring that session back.
    if (nonce == info.probe_echo && index > seen.challenge_index) {
      seen.session = info.session;
      seen.clock_us = info.session_clock_us;
      seen.challenge_index = index;
      seen.output_clock_us = -1;
      return InfoVerdict::kNewSession;
    }
  }
  return InfoVerdict::kUnconfirmed;
}

InfoVerdict InfoGuard::VerifyOutput(const Key& key, const sarmap::pm_output_t& output) {
  if (IsUnsigned(output.hmac_sha256)) return InfoVerdict::kUnsigned;
  if (!SignatureValid(key, output)) return InfoVerdict::kForged;
  auto it = seen_.find(output.deputy_id);
  if (it == seen_.end() || it->second.session == 0 || output.session != it->second.session) {
    return InfoVerdict::kUnconfirmed;
  }
  if (output.session_clock_us <= it->second.output_clock_us) return InfoVerdict::kStale;
  it->second.output_clock_us = output.session_clock_us;
  return InfoVerdict::kAccepted;
}

int64_t InfoGuard::Session(const std::string& deputy_id) const {
  auto it = seen_.find(deputy_id);
  return it == seen_.end() ? 0 : it->second.session;
}

}  // namespace procman
}  // namespace sarmap
