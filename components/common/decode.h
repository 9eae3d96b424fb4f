#pragma once
// DecodeMessage<T>: the one way sarmap turns bytes from the bus or from a log into a message.
//
//   std::string why;
//   sarmap::pose_t pose;
//   if (!common::DecodeMessage(data, size, &pose, &why)) { count, log `why`, drop; }
//
// Three steps, each only when the one before passed: CheckWire<T> (the encoding is safe to
// hand to the generated decoder: common/wire_check.h), T::decode, CheckMessage (the decoded
// values are sane: common/message_checks.h). Nothing a sender puts in the bytes makes it
// crash, throw or allocate more than the bytes justify.
//
// A message from a signed bus (common/bus_auth.h) is read as the message it carries: when the
// whole datagram is not an acceptable T but ends with a bus trailer, the bytes before the trailer
// are tried. Only a node that holds the bus key verifies the trailer (common::Node does, before
// it decodes).

#include <exception>
#include <string>

#include "common/bus_trailer.h"
#include "common/message_checks.h"
#include "common/wire_check.h"

namespace sarmap {
namespace common {

// False with a one-line reason in *why (optional) when `data` is not an acceptable T;
// *out is then unspecified.
// No LCM message is larger than LCM's own maximum (256 MB). liblcm 1.3.1 hands on a 4-8 byte
// "LC02" datagram as a message of 2^32 - 5 bytes made of whatever its buffer held: a size above
// this is refused before any byte past the header is looked at (the bus trailer sits at the end).
constexpr size_t kMaxMessageBytes = size_t{1} << 28;

template <class T>
bool DecodeMessage(const void* data, size_t size, T* out, std::string* why = nullptr) {
  if (size > kMaxMessageBytes) {
    if (why) *why = std::string(T::getTypeName()) + ": impossible size " + std::to_string(size);
    return false;
  }
  if (!CheckWire<T>(data, size, why)) {
    if (!HasBusTrailer(data, size) || !CheckWire<T>(data, size - kBusTrailerBytes, nullptr))
      return false;
    size -= kBusTrailerBytes;
  }
  int decoded = -1;
  try {
    decoded = out->decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {  // not expected after CheckWire; kept as a backstop
    if (why) *why = std::string(T::getTypeName()) + ": decoder threw: " + e.what();
    return false;
  }
  if (decoded != static_cast<int>(size)) {
    if (why)
      *why = std::string(T::getTypeName()) + ": decoder read " + std::to_string(decoded) + " of " +
             std::to_string(size) + " bytes";
    return false;
  }
  const std::string problem = CheckMessage(*out);
  if (!problem.empty()) {
    if (why) *why = std::string(T::getTypeName()) + ": " + problem;
    return false;
  }
  return true;
}

}  // namespace common
}  // namespace sarmap
