#include "common/command_auth.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace sarmap {
namespace common {

AuthKey LoadAuthKeyFile(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) {
    const size_t slash = path.rfind('/');
    const std::string mkdir = slash == std::string::npos || slash == 0
                                  ? ""
                                  : "mkdir -p " + path.substr(0, slash) + " && ";
    throw std::runtime_error("key file " + path + ": " + strerror(errno) +
                             " (create one: " + mkdir + "head -c 32 /dev/urandom > " + path +
                             " && chmod 600 " + path + ")");
  }
  if (st.st_mode & (S_IRWXG | S_IRWXO)) {
    throw std::runtime_error("key file " + path + " is accessible by group or others; chmod 600 " +
                             path);
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("key file " + path + ": cannot read");
  AuthKey key((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (key.size() < 16) {
    throw std::runtime_error(
        "key file " + path + " holds " + std::to_string(key.size()) +
        " bytes; at least 16 random bytes are needed (head -c 32 /dev/urandom)");
  }
  return key;
}

AuthDigest HmacSha256(const AuthKey& key, const uint8_t* data, size_t size) {
  AuthDigest digest{};
  unsigned int length = 0;
  if (!HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), data, size, digest.data(),
            &length) ||
      length != digest.size()) {
    throw std::runtime_error("HMAC-SHA256 failed");
  }
  return digest;
}

bool DigestsEqual(const AuthDigest& a, const uint8_t* b) {
  return CRYPTO_memcmp(a.data(), b, a.size()) == 0;
}

}  // namespace common
}  // namespace sarmap
