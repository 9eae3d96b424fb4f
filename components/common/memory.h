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

// Gives the pages of freed blocks back to the system (glibc's malloc_trim(0)), the free pages
// between live blocks included. Without it a process keeps the pages of its largest recent
// burst (a map redrawn, an optimisation, a state file written), so its resident size reports
// that burst for as long as it runs. Takes about 1-25 ms on a heap of 100 MB; returns whether
// any memory was given back.
bool ReleaseFreeMemory();
// How often a long-running process (every node, the mission bench) calls it, s.
constexpr double kReleaseFreeMemoryPeriod_s = 10.0;

}  // namespace common
}  // namespace sarmap
