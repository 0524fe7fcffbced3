// The open list of the guidance's space-time A* (local_guidance.hpp): a binary heap of
// (f, t, id) entries, the lowest f on top and, among equal f, the deepest t, so that free paths
// are found almost without branching.
//
// Speed without a change of result: it makes the same moves as std::push_heap and std::pop_heap
// under that order, so entries equal in f and t come out in the same order as with the library
// (test/core/open_list_test.cpp checks it), but
// - f and t are packed into one integer (a non-negative float's bits order as the float does),
//   so a comparison is one instruction;
// - the moving entry stays in registers. The library's versions store it and read it back at
//   once, a store-forwarding stall that took a third of the search's time (docs/results.md,
//   "Guidance search speed").
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace gdrhcr {

class OpenList {
 public:
  void clear() { heap_.clear(); }
  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size(); }

  // f must be >= 0 (a cost plus a distance), t >= 0.
  void push(float f, int32_t t, int32_t id) {
    const uint64_t key = order(f, t);
    std::ptrdiff_t hole = static_cast<std::ptrdiff_t>(heap_.size());
    heap_.emplace_back();
    while (hole > 0) {
      const std::ptrdiff_t parent = (hole - 1) / 2;
      if (heap_[parent].key <= key) break;
      heap_[hole] = heap_[parent];
      hole = parent;
    }
    heap_[hole].key = key, heap_[hole].id = id;
  }

  // Removes the top entry and returns its id. Not on an empty list.
  int32_t pop() {
    const int32_t top = heap_.front().id;
    const Entry last = heap_.back();
    heap_.pop_back();
    const std::ptrdiff_t len = static_cast<std::ptrdiff_t>(heap_.size());
    if (len == 0) return top;
    std::ptrdiff_t hole = 0, child = 0;
    while (child < (len - 1) / 2) {  // down to a leaf along the better children
      child = 2 * (child + 1);
      if (heap_[child].key > heap_[child - 1].key) --child;
      heap_[hole] = heap_[child];
      hole = child;
    }
    if ((len & 1) == 0 && child == (len - 2) / 2) {
      child = 2 * (child + 1);
      heap_[hole] = heap_[child - 1];
      hole = child - 1;
    }
    while (hole > 0) {  // then the last entry up from there
      const std::ptrdiff_t parent = (hole - 1) / 2;
      if (heap_[parent].key <= last.key) break;
      heap_[hole] = heap_[parent];
      hole = parent;
    }
    heap_[hole] = last;
    return top;
  }

 private:
  struct Entry {
    uint64_t key;  // f's bits, then the bits of ~t: lower is better
    int32_t id;
  };
  static uint64_t order(float f, int32_t t) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    return (uint64_t{bits} << 32) | (UINT32_MAX - static_cast<uint32_t>(t));
  }
  std::vector<Entry> heap_;
};

}  // namespace gdrhcr
