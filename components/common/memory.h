#pragma once
// What a process holds in memory. No LCM.
//
// The resident size counts the pages the process touches: its data, the code and libraries,
// and the free blocks the allocator keeps for reuse. The heap in use counts the blocks handed
// out and not yet freed. Over a long mission the two tell growth of the data from memory the
// allocator keeps.

#include <cstddef>

namespace sarmap {
namespace common {

constexpr double Megabytes(size_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); }

// The process's resident set (VmRSS of /proc/self/status), MB; 0 when unreadable.
double ResidentMegabytes();
// Bytes the allocator has handed out and not had back (every arena and mmap), MB.
double HeapInUseMegabytes();

}  // namespace common
}  // namespace sarmap
