#pragma once
// Multi-process tests publish real UDP multicast, so they run only where no real network can
// be reached: inside the private namespace of tests/harness/sarmap-netns (ctest runs them
// there), whose only interface is loopback.

#include <net/if.h>

#include <cstring>

namespace sarmap {

// True when loopback is this process's only network interface.
inline bool IsolatedNetwork() {
  struct if_nameindex* interfaces = if_nameindex();
  if (interfaces == nullptr) return false;
  bool only_loopback = true;
  for (const struct if_nameindex* i = interfaces; i->if_index != 0; ++i) {
    only_loopback = only_loopback && std::strcmp(i->if_name, "lo") == 0;
  }
  if_freenameindex(interfaces);
  return only_loopback;
}

}  // namespace sarmap
