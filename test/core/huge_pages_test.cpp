// The huge-page pool behind large distance rows: blocks are usable, aligned, reused by size, and
// small blocks stay on the ordinary heap. Whether the kernel backs the slabs with huge pages is
// its setting (THP), so that is not asserted here; docs/results.md has the measured effect.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "gdrhcr/huge_pages.hpp"

using namespace gdrhcr;

TEST(HugePages, LargeBlocksAreAlignedWritableAndReusedBySize) {
  const size_t bytes = huge_pages::kMinBytes * 3 + 5;
  char* a = static_cast<char*>(huge_pages::allocate(bytes));
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(a) % 64, 0u);
  std::memset(a, 0xAB, bytes);
  char* b = static_cast<char*>(huge_pages::allocate(bytes));
  EXPECT_NE(a, b);
  EXPECT_TRUE(b + bytes <= a || a + bytes <= b) << "two live blocks overlap";
  std::memset(b, 0xCD, bytes);
  EXPECT_EQ(static_cast<unsigned char>(a[bytes - 1]), 0xAB);
  huge_pages::release(a, bytes);
  EXPECT_EQ(huge_pages::allocate(bytes), a) << "a released block is handed out again for its size";
  huge_pages::release(a, bytes);
  huge_pages::release(b, bytes);
}

TEST(HugePages, SmallBlocksDoNotTakeSlabs) {
  const size_t before = huge_pages::slab_bytes();
  std::vector<void*> blocks;
  for (int k = 0; k < 100; ++k) blocks.push_back(huge_pages::allocate(huge_pages::kMinBytes - 1));
  EXPECT_EQ(huge_pages::slab_bytes(), before);
  for (void* p : blocks) huge_pages::release(p, huge_pages::kMinBytes - 1);
}

TEST(HugePages, VectorsHoldTheirValuesAcrossGrowth) {
  std::vector<uint32_t, HugePageAllocator<uint32_t>> v;
  for (uint32_t k = 0; k < 300000; ++k) v.push_back(k * 7);  // grows from the heap into slabs
  for (uint32_t k = 0; k < 300000; k += 997) ASSERT_EQ(v[k], k * 7);
  EXPECT_GE(huge_pages::slab_bytes(), v.capacity() * sizeof(uint32_t));
}
