#include "procman/order_auth.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sarmap {
namespace procman {

std::string DefaultKeyPath() {
  const char* env = getenv("SARMAP_PROCMAN_KEY");
  if (env && *env) return env;
  const char* home = getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.config/sarmap/procman.key";
}

Key LoadKeyFile(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) {
    throw std::runtime_error(
        "key file " + path + ": " + strerror(errno) +
        " (create one: mkdir -p ~/.config/sarmap && head -c 32 /dev/urandom > " + path +
        " && chmod 600 " + path + ")");
  }
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    throw std::runtime_error("key file " + path + " is accessible by group or others; chmod 600 " +
                             path);
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("key file " + path + ": cannot read");
  Key key((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (key.size() < kMinKeyBytes) {
    throw std::runtime_error("key file " + path + " holds " + std::to_string(key.size()) +
                             " bytes; at least " + std::to_string(kMinKeyBytes) +
                             " random bytes are needed (head -c 32 /dev/urandom)");
  }
  return key;
}

Digest HmacSha256(const Key& key, const uint8_t* data, size_t size) {
  Digest digest{};
  unsigned int length = 0;
  if (!HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), data, size, digest.data(),
            &length) ||
      length != digest.size()) {
    throw std::runtime_error("HMAC-SHA256 failed");
  }
  return digest;
}

namespace {

// False when `orders` has no LCM encoding: LCM's encoder writes a string up to its first NUL
// while getEncodedSize() counts every byte, so a string holding a NUL (which only a hostile
// sender puts there) cannot be encoded.
bool OrdersDigest(const Key& key, const sarmap::pm_orders_t& orders, Digest* digest) {
  sarmap::pm_orders_t copy = orders;
  std::fill(std::begin(copy.hmac_sha256), std::end(copy.hmac_sha256), 0);
  const int size = copy.getEncodedSize();
  std::vector<uint8_t> buffer(static_cast<size_t>(size));
  if (copy.encode(buffer.data(), 0, size) != size) return false;
  *digest = HmacSha256(key, buffer.data(), buffer.size());
  return true;
}

}  // namespace

void SignOrders(const Key& key, sarmap::pm_orders_t* orders) {
  Digest d;
  if (!OrdersDigest(key, *orders, &d)) {
    throw std::runtime_error("cannot encode pm_orders_t (a string holds a NUL byte)");
  }
  std::copy(d.begin(), d.end(), std::begin(orders->hmac_sha256));
}

bool SignatureValid(const Key& key, const sarmap::pm_orders_t& orders) {
  Digest d;
  if (!OrdersDigest(key, orders, &d)) return false;
  return CRYPTO_memcmp(d.data(), orders.hmac_sha256, d.size()) == 0;
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
  }
  return "?";
}

std::string ReplayDomain(const std::string& sheriff_id) {
  return sheriff_id.substr(0, sheriff_id.find('/'));
}

ReplayGuard::ReplayGuard(std::string state_path, int64_t window_us)
    : state_path_(std::move(state_path)), window_us_(window_us) {
  if (state_path_.empty()) return;
  std::ifstream in(state_path_);
  if (!in) {
    if (errno == ENOENT) return;  // first run
    throw std::runtime_error("replay state " + state_path_ + ": " + strerror(errno));
  }
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    // "<counter> <sheriff id>": the id may contain spaces, the counter cannot.
    const size_t space = line.find(' ');
    char* end = nullptr;
    const long long counter = strtoll(line.c_str(), &end, 10);
    if (space == std::string::npos || end != line.c_str() + space || counter < 0) {
      throw std::runtime_error("replay state " + state_path_ + ":" + std::to_string(line_no) +
                               ": corrupt line (delete the file only if no replay can matter)");
    }
    last_[line.substr(space + 1)] = counter;
  }
}

int64_t ReplayGuard::Last(const std::string& sheriff_id) const {
  auto it = last_.find(sheriff_id);
  return it == last_.end() ? -1 : it->second;
}

int64_t ReplayGuard::Newest(const std::string& sheriff_id) const {
  const std::string name = ReplayDomain(sheriff_id);
  int64_t newest = -1;
  for (const auto& [id, c] : last_) {
    if (ReplayDomain(id) == name) newest = std::max(newest, c);
  }
  return newest;
}

bool ReplayGuard::Fresh(const std::string& sheriff_id, int64_t counter) const {
  const int64_t last = Last(sheriff_id);
  const int64_t newest = Newest(sheriff_id);
  if (last >= 0 && counter <= last) return false;
  return newest < 0 || counter > newest - window_us_;
}

bool ReplayGuard::Accept(const std::string& sheriff_id, int64_t counter) {
  last_[sheriff_id] = std::max(counter, Last(sheriff_id));
  // Forget instances of this name that fell out of the window: the NAME rule refuses them.
  const std::string name = ReplayDomain(sheriff_id);
  const int64_t newest = Newest(sheriff_id);
  for (auto it = last_.begin(); it != last_.end();) {
    if (ReplayDomain(it->first) == name && it->second < newest - window_us_) {
      it = last_.erase(it);
    } else {
      ++it;
    }
  }
  if (state_path_.empty()) return true;
  // Write a new file and rename it over the old one: a crash never leaves half a file.
  const std::string tmp = state_path_ + ".tmp";
  FILE* f = fopen(tmp.c_str(), "w");
  if (!f) return false;
  bool ok = true;
  for (const auto& [id, c] : last_) {
    ok = ok && fprintf(f, "%lld %s\n", static_cast<long long>(c), id.c_str()) > 0;
  }
  ok = fflush(f) == 0 && ok;
  ok = fsync(fileno(f)) == 0 && ok;
  ok = fclose(f) == 0 && ok;
  return ok && rename(tmp.c_str(), state_path_.c_str()) == 0;
}

Verdict VerifyOrders(const Key& key, const sarmap::pm_orders_t& orders, ReplayGuard* guard,
                     bool* persisted) {
  bool all_zero = true;
  for (uint8_t b : orders.hmac_sha256) all_zero = all_zero && b == 0;
  if (all_zero) return Verdict::kUnsigned;
  if (!SignatureValid(key, orders)) return Verdict::kForged;
  if (!guard->Fresh(orders.sheriff_id, orders.counter)) return Verdict::kReplayed;
  const bool ok = guard->Accept(orders.sheriff_id, orders.counter);
  if (persisted) *persisted = ok;
  return Verdict::kAccepted;
}

int64_t CounterSource::Next() {
  const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  last_ = std::max(last_ + 1, now_us);
  return last_;
}

}  // namespace procman
}  // namespace sarmap
