#include "common/bus_auth.h"

#include <openssl/core_names.h>
#include <openssl/evp.h>
#include <openssl/params.h>
#include <openssl/rand.h>

#include <algorithm>
#include <stdexcept>

namespace sarmap {
namespace common {
namespace {

uint64_t ReadBigEndian64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return v;
}

void WriteBigEndian64(uint64_t v, uint8_t* p) {
  for (int i = 7; i >= 0; --i, v >>= 8) p[i] = static_cast<uint8_t>(v & 0xff);
}

}  // namespace

BusAuth::BusAuth() = default;

BusAuth::BusAuth(AuthKey key) : key_(std::move(key)) {
  if (RAND_bytes(session_.data(), static_cast<int>(session_.size())) != 1) {
    throw std::runtime_error("no random bytes for the bus session");
  }
}

AuthDigest BusAuth::Digest(const std::string& channel, const uint8_t* data, size_t payload_size,
                           const uint8_t* trailer_head) const {
  // channel | 0x00 | encoding | magic | session | counter, in one HMAC context.
  AuthDigest digest{};
  // Fetched once for the process (an algorithm lookup), kept to its end.
  static EVP_MAC* const mac = EVP_MAC_fetch(nullptr, "HMAC", nullptr);
  EVP_MAC_CTX* ctx = mac ? EVP_MAC_CTX_new(mac) : nullptr;
  char sha256[] = "SHA256";
  const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(OSSL_MAC_PARAM_DIGEST, sha256, 0),
                               OSSL_PARAM_construct_end()};
  size_t length = 0;
  const uint8_t zero = 0;
  const bool ok =
      ctx && EVP_MAC_init(ctx, key_.data(), key_.size(), params) &&
      EVP_MAC_update(ctx, reinterpret_cast<const uint8_t*>(channel.data()), channel.size()) &&
      EVP_MAC_update(ctx, &zero, 1) && EVP_MAC_update(ctx, data, payload_size) &&
      EVP_MAC_update(ctx, trailer_head, kBusTrailerBytes - digest.size()) &&
      EVP_MAC_final(ctx, digest.data(), &length, digest.size()) && length == digest.size();
  EVP_MAC_CTX_free(ctx);
  if (!ok) throw std::runtime_error("HMAC-SHA256 failed");
  return digest;
}

void BusAuth::Sign(const std::string& channel, std::vector<uint8_t>* encoding) {
  if (!keyed()) return;
  const size_t payload = encoding->size();
  encoding->resize(payload + kBusTrailerBytes);
  uint8_t* trailer = encoding->data() + payload;
  std::copy(std::begin(kBusTrailerMagic), std::end(kBusTrailerMagic), trailer);
  std::copy(session_.begin(), session_.end(), trailer + 4);
  WriteBigEndian64(++counter_, trailer + 12);
  const AuthDigest d = Digest(channel, encoding->data(), payload, trailer);
  std::copy(d.begin(), d.end(), trailer + 20);
}

bool BusAuth::Verify(const std::string& channel, const uint8_t* data, size_t size,
                     size_t* payload_size, std::string* why) {
  *payload_size = size;
  if (!keyed()) return true;
  if (!HasBusTrailer(data, size)) {
    if (why) *why = "not signed with the bus key (no trailer)";
    return false;
  }
  const size_t payload = size - kBusTrailerBytes;
  const uint8_t* trailer = data + payload;
  if (!DigestsEqual(Digest(channel, data, payload, trailer), trailer + 20)) {
    if (why) *why = "bad bus signature (forged, altered, another key or another channel)";
    return false;
  }
  const uint64_t session = ReadBigEndian64(trailer + 4);
  const uint64_t counter = ReadBigEndian64(trailer + 12);
  auto& channel_sessions = sessions_[channel];
  auto it = channel_sessions.find(session);
  if (it != channel_sessions.end() && counter <= it->second.last_counter) {
    if (why) *why = "a signed message heard before (played back)";
    return false;
  }
  if (it == channel_sessions.end()) {
    if (channel_sessions.size() >= kBusSessionsPerChannel) {
      // Forget the session that passed least recently: a publisher that has gone.
      auto oldest = std::min_element(
          channel_sessions.begin(), channel_sessions.end(),
          [](const auto& a, const auto& b) { return a.second.last_used < b.second.last_used; });
      channel_sessions.erase(oldest);
    }
    it = channel_sessions.emplace(session, SessionState{}).first;
  }
  it->second.last_counter = counter;
  it->second.last_used = ++verified_;
  *payload_size = payload;
  return true;
}

}  // namespace common
}  // namespace sarmap
