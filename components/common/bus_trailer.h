#pragma once
// The signed bus's trailer (common/bus_auth.h), as far as a reader without the key needs it:
// 52 bytes after a message's LCM encoding,
//   "SMB1" | session (8 bytes) | counter (8 bytes, big-endian) | HMAC-SHA256 (32 bytes).
// An LCM encoding's length is fixed by its own contents, so a trailer is never mistaken for part
// of a message: DecodeMessage (common/decode.h) first decodes the whole datagram and only when
// that fails tries it without a trailer that starts with the magic.

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace sarmap {
namespace common {

constexpr char kBusTrailerMagic[4] = {'S', 'M', 'B', '1'};
constexpr size_t kBusTrailerBytes = 4 + 8 + 8 + 32;

// True when the last kBusTrailerBytes of `data` start with the trailer's magic.
inline bool HasBusTrailer(const void* data, size_t size) {
  if (size < kBusTrailerBytes) return false;
  const uint8_t* at = static_cast<const uint8_t*>(data) + size - kBusTrailerBytes;
  return std::memcmp(at, kBusTrailerMagic, sizeof(kBusTrailerMagic)) == 0;
}

}  // namespace common
}  // namespace sarmap
