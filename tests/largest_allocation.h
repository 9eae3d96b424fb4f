#pragma once
// The largest single allocation within a window of code: proves that a hostile count is
// refused before anything sizes a vector from it. Linking largest_allocation.cc replaces the
// binary's global operator new (with malloc) to measure.

#include <cstddef>

namespace sarmap {
namespace testing {

// Starts a window: allocations from now on are measured.
void StartMeasuringAllocations();
// Ends the window: later allocations are not measured.
void StopMeasuringAllocations();
// The largest single allocation of the current (or last) window.
size_t LargestAllocation();

}  // namespace testing
}  // namespace sarmap
