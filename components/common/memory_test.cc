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

// 80 MB in 40 kB blocks, each followed by a small block that stays: freed, the large blocks
// leave free pages between live ones, which the allocator keeps until they are released.
TEST(MemoryTest, ReleasingFreeMemoryGivesBackThePagesBetweenLiveBlocks) {
  constexpr size_t kBlocks = 2000, kLargeBytes = 40000, kSmallBytes = 100;
  std::vector<std::unique_ptr<char[]>> large(kBlocks), small(kBlocks);
  for (size_t i = 0; i < kBlocks; ++i) {
    large[i].reset(new char[kLargeBytes]);
    std::memset(large[i].get(), 1, kLargeBytes);
    small[i].reset(new char[kSmallBytes]);
    std::memset(small[i].get(), 1, kSmallBytes);
  }
  for (auto& b : large) b.reset();
  const double rss_freed = ResidentMegabytes();
  ReleaseFreeMemory();
  EXPECT_LT(ResidentMegabytes(), rss_freed - 50.0);
  EXPECT_NE(small.back().get(), nullptr);
}

}  // namespace
}  // namespace common
}  // namespace sarmap
