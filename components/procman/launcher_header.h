#pragma once
// The header of the launcher's own messages: PM_ORDERS, PM_INFO, PM_OUTPUT and the deputy's
// NODE_STATUS.

#include <cstdint>

#include "common/time.h"
#include "sarmap/header_t.hpp"

namespace sarmap {
namespace procman {

// Stamped with the wall clock, numbered by `*seq` (then incremented), in no frame.
inline sarmap::header_t LauncherHeader(int64_t* seq) {
  sarmap::header_t header;
  header.utime = common::WallClockUtime();
  header.seq = (*seq)++;
  header.frame = "";
  return header;
}

}  // namespace procman
}  // namespace sarmap
