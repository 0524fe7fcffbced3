// Large arrays on transparent huge pages (Linux THP), for data read at random across gigabytes.
//
// Distance rows (dist_table.hpp) are the case: PIBT over 10,000 agents reads a few cache lines
// from each agent's row, and on warehouse_large every row of every free cell is 4.5 GB. On 4 KB
// pages each such read also misses the TLB, and under virtualisation a page walk costs several
// memory reads more. Memory from mmap is huge-page backed only where asked for with
// madvise(MADV_HUGEPAGE) when the kernel's THP mode is "madvise" (Debian's default), and only
// in whole 2 MB pages, so a row of its own (tens to hundreds of KB) never gets one.
//
// huge_pages::allocate carves blocks of kMinBytes or more from 64 MB slabs aligned to 2 MB and
// advised for huge pages; a released block goes to a free list of its size and is handed out
// again for that size (rows of one table all have the same size, so eviction under a memory
// budget reuses them). Slabs are kept until the process ends. Smaller blocks, other systems and
// kernels without THP get plain operator new; nothing else changes.
#pragma once

#include <cstddef>
#include <new>

namespace gdrhcr {
namespace huge_pages {

constexpr size_t kMinBytes = size_t(64) << 10;  // smaller blocks come from operator new
void* allocate(size_t bytes);
void release(void* p, size_t bytes);
// Bytes held in slabs (in use or on free lists), for reports and tests.
size_t slab_bytes();

}  // namespace huge_pages

// A std::allocator for vectors that may hold kMinBytes or more (see above).
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  T* allocate(size_t n) { return static_cast<T*>(huge_pages::allocate(n * sizeof(T))); }
  void deallocate(T* p, size_t n) { huge_pages::release(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const { return false; }
};

}  // namespace gdrhcr
