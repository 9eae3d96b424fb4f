#include "common/command_auth.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <vector>

namespace sarmap {
namespace common {

std::string ExpandUserHome(const std::string& path) {
  if (path != "~" && path.rfind("~/", 0) != 0) return path;
  passwd entry;
  passwd* found = nullptr;
  std::vector<char> buffer(16384);
  if (getpwuid_r(getuid(), &entry, buffer.data(), buffer.size(), &found) != 0 || !found ||
      !found->pw_dir || !*found->pw_dir) {
    throw std::runtime_error(path + ": no home directory for user " + std::to_string(getuid()));
  }
  return std::string(found->pw_dir) + path.substr(1);
}

AuthKey LoadAuthKeyFile(const std::string& path_as_given) {
  const std::string path = ExpandUserHome(path_as_given);
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
