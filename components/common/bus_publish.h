#pragma once
// Publishing on a bus that may be signed (common/bus_auth.h): for the processes that hold an
// lcm::LCM of their own (the procman deputy); common::Node's publishers do the same.

#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "common/bus_auth.h"

namespace sarmap {
namespace common {

// Publishes `msg` on `channel`, with the bus trailer when `auth` is keyed. False when the
// message has no LCM encoding (a string holding a NUL byte) or liblcm refuses it.
template <class T>
bool PublishOnBus(lcm::LCM* lcm, BusAuth* auth, const std::string& channel, const T& msg) {
  if (!auth || !auth->keyed()) return lcm->publish(channel, &msg) == 0;
  const int size = msg.getEncodedSize();
  if (size <= 0) return false;
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  if (msg.encode(bytes.data(), 0, size) != size) return false;
  auth->Sign(channel, &bytes);
  return lcm->publish(channel, bytes.data(), static_cast<unsigned int>(bytes.size())) == 0;
}

}  // namespace common
}  // namespace sarmap
