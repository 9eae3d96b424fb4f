#pragma once
// Keys for the tests of signed commands, orders and buses: 32 bytes that differ with the seed,
// the same on every run.

#include <cstddef>
#include <cstdint>

#include "common/command_auth.h"

namespace sarmap {
namespace common {
namespace testing_util {

inline AuthKey TestKey(uint8_t seed) {
  AuthKey key(32);
  for (size_t i = 0; i < key.size(); ++i) key[i] = static_cast<uint8_t>(seed + 7 * i);
  return key;
}

}  // namespace testing_util
}  // namespace common
}  // namespace sarmap
