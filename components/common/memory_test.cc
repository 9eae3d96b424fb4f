#include "common/memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

namespace sarmap {
namespace common {
namespace {

// 160 MB in small blocks, written so that their pages are resident: both figures grow by it.
// Freed, the heap in use falls back; the resident size need not (the allocator keeps pages
// below a live block).
TEST(MemoryTest, HeapInUseAndResidentSizeFollowAllocations) {
  const double rss_before = ResidentMegabytes();
  const double heap_before = HeapInUseMegabytes();
  ASSERT_GT(rss_before, 0.0);
  constexpr size_t kBlocks = 40000, kBytes = 4000;
  std::vector<std::unique_ptr<char[]>> blocks(kBlocks);
  for (auto& b : blocks) {
    b.reset(new char[kBytes]);
    std::memset(b.get(), 1, kBytes);
  }
  EXPECT_GT(HeapInUseMegabytes() - heap_before, 140.0);
  EXPECT_GT(ResidentMegabytes() - rss_before, 140.0);
  for (size_t i = 0; i + 1 < kBlocks; ++i) blocks[i].reset();
  EXPECT_LT(HeapInUseMegabytes() - heap_before, 10.0);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
