// Slabs advised for transparent huge pages (see huge_pages.hpp).
#include "gdrhcr/huge_pages.hpp"

#include <cstdint>
#include <mutex>
#include <unordered_map>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace gdrhcr {
namespace huge_pages {
namespace {

constexpr size_t kHugePage = size_t(2) << 20;
constexpr size_t kSlab = size_t(64) << 20;
constexpr size_t kAlign = 64;  // blocks start on cache lines

struct Pool {
  std::mutex mutex;
  std::unordered_map<size_t, std::vector<void*>> free_blocks;  // by rounded size
  char* next = nullptr;  // the current slab's unused part
  size_t left = 0;
  std::vector<std::pair<uintptr_t, uintptr_t>> ranges;  // each slab's [begin, end)
  size_t slabs = 0;      // bytes
  bool unavailable = false;  // mmap failed once: operator new from then on
  bool in_slab(const void* block) const {
    const uintptr_t a = reinterpret_cast<uintptr_t>(block);
    for (auto& [b, e] : ranges)
      if (a >= b && a < e) return true;
    return false;
  }
};

Pool& pool() {
  static Pool* p = new Pool;  // never destroyed: blocks may be released during static destruction
  return *p;
}

size_t round_up(size_t x, size_t to) { return (x + to - 1) / to * to; }
size_t rounded(size_t bytes) { return round_up(bytes, kAlign); }

#ifdef __linux__
// A slab of `size` bytes (a multiple of kHugePage), 2 MB aligned, advised for huge pages; nullptr
// if mmap fails.
char* new_slab(size_t size) {
  void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) return nullptr;
  const uintptr_t start = reinterpret_cast<uintptr_t>(raw);
  const uintptr_t aligned = round_up(start, kHugePage);
  if (aligned > start) munmap(raw, aligned - start);  // trim to the 2 MB boundary on both sides
  const uintptr_t end = start + size + kHugePage;
  if (end > aligned + size) munmap(reinterpret_cast<void*>(aligned + size), end - aligned - size);
  madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);  // a kernel without THP refuses: fine
  return reinterpret_cast<char*>(aligned);
}
#else
char* new_slab(size_t) { return nullptr; }
#endif

}  // namespace

void* allocate(size_t bytes) {
  if (bytes < kMinBytes) return ::operator new(bytes);
  const size_t size = rounded(bytes);
  Pool& p = pool();
  std::lock_guard<std::mutex> lock(p.mutex);
  if (p.unavailable) return ::operator new(bytes);
  auto it = p.free_blocks.find(size);
  if (it != p.free_blocks.end() && !it->second.empty()) {
    void* block = it->second.back();
    it->second.pop_back();
    return block;
  }
  if (p.left < size) {
    const size_t slab = round_up(size > kSlab ? size : kSlab, kHugePage);
    char* s = new_slab(slab);
    if (!s) {
      p.unavailable = true;
      return ::operator new(bytes);
    }
    p.next = s;
    p.left = slab;
    p.slabs += slab;
    p.ranges.emplace_back(reinterpret_cast<uintptr_t>(s), reinterpret_cast<uintptr_t>(s) + p.left);
  }
  void* block = p.next;
  p.next += size;
  p.left -= size;
  return block;
}

void release(void* block, size_t bytes) {
  if (!block) return;
  if (bytes < kMinBytes) return ::operator delete(block);
  Pool& p = pool();
  std::lock_guard<std::mutex> lock(p.mutex);
  if (!p.in_slab(block)) return ::operator delete(block);  // given after mmap failed
  p.free_blocks[rounded(bytes)].push_back(block);
}

size_t slab_bytes() {
  Pool& p = pool();
  std::lock_guard<std::mutex> lock(p.mutex);
  return p.slabs;
}

}  // namespace huge_pages
}  // namespace gdrhcr
