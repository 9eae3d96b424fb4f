#include "tests/largest_allocation.h"

#include <cstdlib>
#include <new>

namespace {
bool g_measuring = false;
size_t g_largest_allocation = 0;
}  // namespace

// free() on what operator new returned is right here: this operator new is malloc.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(size_t size) {
  if (g_measuring && size > g_largest_allocation) g_largest_allocation = size;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace sarmap {
namespace testing {

void StartMeasuringAllocations() {
  g_largest_allocation = 0;
  g_measuring = true;
}

void StopMeasuringAllocations() { g_measuring = false; }

size_t LargestAllocation() { return g_largest_allocation; }

}  // namespace testing
}  // namespace sarmap
